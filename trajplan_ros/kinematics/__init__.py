# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The arm model: a serial chain of revolute joints, its forward kinematics and Jacobian."""
from trajplan_ros.kinematics.arm import ArmModel, ToolJacobian
from trajplan_ros.kinematics.errors import InvalidArmModel
from trajplan_ros.kinematics.paper_arm import paper_arm

__all__ = ['ArmModel', 'InvalidArmModel', 'ToolJacobian', 'paper_arm']
