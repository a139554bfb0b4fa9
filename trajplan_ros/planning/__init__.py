# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Direct trajectory planning: objective, fuzzy shaping, optimisers, trajectory and ``plan``."""
from trajplan_ros.planning.fuzzy import RewardPunishment
from trajplan_ros.planning.motion_profile import JointLimits, MotionProfile, read_joint_limits
from trajplan_ros.planning.objective import InvalidRequest, Mode, Objective
from trajplan_ros.planning.planner import (ALGORITHMS, DEFAULT_AXIS_TOLERANCE,
                                           DEFAULT_TOLERANCE, plan, PlanResult, PlanStatus,
                                           prepare)
from trajplan_ros.planning.trajectory import (motion_trajectory, servo_trajectory, Trajectory,
                                              trajectory_points)

__all__ = [
    'ALGORITHMS', 'DEFAULT_AXIS_TOLERANCE', 'DEFAULT_TOLERANCE', 'InvalidRequest', 'JointLimits',
    'Mode', 'MotionProfile', 'Objective', 'PlanResult', 'PlanStatus', 'RewardPunishment',
    'Trajectory', 'motion_trajectory', 'plan', 'prepare', 'read_joint_limits', 'servo_trajectory',
    'trajectory_points',
]
