# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Direct trajectory planning: ``plan``, and the names a caller of it needs."""
from trajplan_ros.motion.motion_profile import (JointLimits, MotionProfile, Profile,
                                                read_joint_limits, Timing)
from trajplan_ros.motion.trajectory import (motion_trajectory, servo_trajectory, Trajectory,
                                            trajectory_points)
from trajplan_ros.planning.planner import plan, PlanResult, PlanStatus, prepare
from trajplan_ros.planning.request import ALGORITHMS, PlanRequest
from trajplan_ros.search.fuzzy import RewardPunishment
from trajplan_ros.search.goal import (DEFAULT_AXIS_TOLERANCE, DEFAULT_ORIENTATION_TOLERANCE,
                                      DEFAULT_TOLERANCE, Goal, InvalidRequest, Mode)
from trajplan_ros.search.objective import Objective

__all__ = [
    'ALGORITHMS', 'DEFAULT_AXIS_TOLERANCE', 'DEFAULT_ORIENTATION_TOLERANCE', 'DEFAULT_TOLERANCE',
    'Goal', 'InvalidRequest', 'JointLimits',
    'Mode', 'MotionProfile', 'Objective', 'PlanRequest', 'PlanResult', 'PlanStatus', 'Profile',
    'RewardPunishment', 'Timing', 'Trajectory', 'motion_trajectory', 'plan', 'prepare',
    'read_joint_limits', 'servo_trajectory', 'trajectory_points',
]
