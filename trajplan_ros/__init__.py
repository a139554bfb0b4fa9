# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
trajplan_ros: direct trajectory planning with IEPSO and fuzzy rewards and punishment.

The package is layered; each layer uses only those listed before it:

* ``kinematics``: the arm model (forward kinematics and Jacobian) and how kernels are compiled
  (``jit``: numba, one cache policy);
* ``motion``: motion in time: the servo law (eq. 10), the trapezoidal and jerk-limited profiles,
  rest-to-rest phases and trajectories;
* ``collision``: the arm's collision shapes, the spheres and hulls that hold them, the pairs to
  skip, the scene, the distances (coal) and the continuous check of a motion;
* ``search``: the objective (eq. 9-14), the fuzzy term, IEPSO and its peers, the polish, the
  solution curves and the search for a free joint goal;
* ``planning``: ``plan``, its request (``PlanRequest``, holding a ``Goal``) and result;
* ``ros``: the ROS 2 node (the only layer besides ``tools`` that imports rclpy);
* ``tools``: the ``trajplan`` command, benchmarks and their reference oracles, figures, the demo.

The names below are the public library API.
"""
from trajplan_ros.collision.distances import ArmCollision, CollisionWorld
from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.collision.scene import Scene
from trajplan_ros.kinematics import ArmModel, InvalidArmModel, paper_arm
from trajplan_ros.planning import (ALGORITHMS, DEFAULT_AXIS_TOLERANCE, DEFAULT_TOLERANCE,
                                   Goal, InvalidRequest, JointLimits, Mode, motion_trajectory,
                                   MotionProfile, Objective, plan, PlanRequest, PlanResult,
                                   PlanStatus, Profile, read_joint_limits, RewardPunishment,
                                   servo_trajectory, Timing, Trajectory, trajectory_points)

__all__ = [
    'ALGORITHMS', 'ArmCollision', 'ArmModel', 'CollisionWorld', 'DEFAULT_AXIS_TOLERANCE',
    'DEFAULT_TOLERANCE', 'Goal', 'InvalidArmModel', 'InvalidCollisionInput', 'Scene',
    'InvalidRequest', 'JointLimits', 'Mode', 'MotionProfile', 'Objective', 'PlanRequest',
    'PlanResult', 'PlanStatus', 'Profile', 'RewardPunishment', 'Timing', 'Trajectory',
    'motion_trajectory', 'paper_arm', 'plan', 'read_joint_limits', 'servo_trajectory',
    'trajectory_points',
]
