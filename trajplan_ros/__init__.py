# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
trajplan_ros: direct trajectory planning with IEPSO and fuzzy rewards and punishment.

The package is layered; each layer uses only those listed before it:

* ``kinematics``: the arm model (forward kinematics and Jacobian) and how kernels are compiled
  (``jit``: numba, one cache policy);
* ``collision``: the arm's collision shapes, the spheres that hold them, the pairs to skip, the
  scene and the distances (coal);
* ``planning``: the objective, the fuzzy shaping, IEPSO and the comparison optimisers, the
  polish, the trajectory and ``plan``: numpy, with the hot loops as compiled kernels;
* ``ros``: the ROS 2 node (the only layer besides ``tools`` that imports rclpy);
* ``tools``: the ``trajplan`` command, benchmarks, figures and the demo.

The names below are the public library API.
"""
from trajplan_ros.collision.distances import ArmCollision, CollisionWorld
from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.collision.scene import Scene
from trajplan_ros.kinematics import ArmModel, InvalidArmModel, paper_arm
from trajplan_ros.planning import (ALGORITHMS, DEFAULT_AXIS_TOLERANCE, DEFAULT_TOLERANCE,
                                   InvalidRequest, JointLimits, Mode, MotionProfile, Objective,
                                   plan, PlanResult, PlanStatus, read_joint_limits,
                                   RewardPunishment, servo_trajectory, Trajectory,
                                   trajectory_points)

__all__ = [
    'ALGORITHMS', 'ArmCollision', 'ArmModel', 'CollisionWorld', 'DEFAULT_AXIS_TOLERANCE',
    'DEFAULT_TOLERANCE', 'InvalidArmModel', 'InvalidCollisionInput', 'Scene',
    'InvalidRequest', 'JointLimits', 'Mode', 'MotionProfile', 'Objective', 'PlanResult',
    'PlanStatus', 'RewardPunishment', 'Trajectory', 'paper_arm', 'plan', 'read_joint_limits',
    'servo_trajectory', 'trajectory_points',
]
