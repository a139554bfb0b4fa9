"""trajplan_ros: direct trajectory planning with IEPSO and fuzzy rewards and punishment.

The planning core (this package minus ``node``) is pure numpy and imports without ROS 2.
"""
from .arm import ArmModel, InvalidArmModel, paper_arm
from .fuzzy import RewardPunishment
from .objective import InvalidRequest, Mode, Objective
from .planner import ALGORITHMS, DEFAULT_TOLERANCE, PlanResult, PlanStatus, plan
from .trajectory import Trajectory, servo_trajectory

__all__ = [
    "ALGORITHMS", "ArmModel", "DEFAULT_TOLERANCE", "InvalidArmModel", "InvalidRequest", "Mode",
    "Objective", "PlanResult", "PlanStatus", "RewardPunishment", "Trajectory", "paper_arm",
    "plan", "servo_trajectory",
]
