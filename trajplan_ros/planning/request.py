# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
``PlanRequest``: everything one plan needs, under the names users know, and its checking.

The goal (``Goal``: its kind, target, tolerances and frame) and start, the arm, the motion's
profile and the collision world; the search's settings (algorithm, swarm size, iteration cap,
convergence precision, seed, fuzzy shaping, optimiser options); the limits on its work
(``max_planning_time``). The names are the node's parameters and the ``trajplan plan`` flags:
``angular_velocity`` (``--angular-velocity``), ``max_iterations``, ``max_planning_time``, and
the goal's ``mode``, ``tolerance``, ``axis_tolerance``, ``orientation_tolerance``.

``validate`` refuses settings with a one-line reason (ValueError); a goal or start the arm
cannot take is not a settings error: ``plan`` answers it REJECTED, with the reason.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
import functools
import inspect
from types import MappingProxyType
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from trajplan_ros.collision.distances import CollisionWorld
from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.motion.motion_profile import MotionProfile, SCALING_KEYS
from trajplan_ros.search.baselines import de, ga, pso, spso
from trajplan_ros.search.fuzzy import RewardPunishment
from trajplan_ros.search.goal import Goal
from trajplan_ros.search.iepso import iepso
from trajplan_ros.search.objective import DEFAULT_OMEGA
from trajplan_ros.search.optimize import OptimizeResult

__all__ = ['ALGORITHMS', 'GOAL_SETTINGS', 'PlanRequest', 'RENAMED']

#: Name -> optimiser; every one takes (objective, population=, max_iter=, tol=, seed=).
ALGORITHMS: dict[str, Callable[..., OptimizeResult]] = {
    'iepso': iepso, 'pso': pso, 'spso': spso, 'ga': ga, 'de': de,
}
#: Earlier keyword names of ``plan`` -> the request's names (the old ones keep working).
RENAMED = MappingProxyType({'omega': 'angular_velocity', 'max_iter': 'max_iterations',
                            'tol': 'convergence_precision', 'profile': 'motion',
                            'options': 'optimizer_options'})
#: ``Goal``'s settings, which ``plan``'s keywords may give beside a position.
GOAL_SETTINGS = frozenset(f.name for f in fields(Goal)) - {'position'}
#: The optimisers' keywords that the request sets itself, not through ``optimizer_options``.
_OWN_KEYWORDS = frozenset({'population', 'max_iter', 'tol', 'seed', 'interrupt'})


@functools.lru_cache(maxsize=1)
def _paper_arm() -> ArmModel:
    """Return the paper's arm, built once for every request without an arm."""
    return paper_arm()


@dataclass(frozen=True)
class PlanRequest:
    """
    One planning request: the goal, where the arm starts, and every setting of the plan.

    :param goal: the goal (``Goal``), or a tool position (x, y, z), m, in the arm's base
        frame: a point goal.
    :param start: all joint angles now (rad); None: the upright pose q = 0.
    :param arm: the arm model; None: the paper's arm.
    :param motion: the motion's profile, timing and limits; the plan minimises its duration.
    :param angular_velocity: the servo angular velocity omega of eq. (10), rad/s; it caps every
        joint's velocity.
    :param world: the arm's collision model, scene and padding: the plan is the fastest direct
        motion found that keeps the padding. None: no collision check.
    :param algorithm: "iepso" (the planner), or "pso", "spso", "ga", "de" to compare.
    :param population: swarm (or population) size.
    :param max_iterations: iteration cap.
    :param convergence_precision: Table 4's convergence precision: the stopping rule's least
        improvement of F.
    :param seed: random seed; the same seed gives the same answer, bit for bit.
    :param shaping: the rewards-and-punishment settings (None: Table 4's).
    :param optimizer_options: further keywords of the optimiser (e.g. {"swarms": 4} for IEPSO).
    :param max_planning_time: longest search (s, monotonic clock); None: no limit.
    :param detours: with a ``world``: where no direct motion to the goal is free, plan the
        fastest free motion found through a via point (``search.detour``).
    :param start_limit_margin: how far (rad) a start joint may lie outside its limits (a
        calibrated arm reads a little past them): it is planned from where it is, the motion
        bringing it inside, with a note in the message; further out, the request is REJECTED.
    """

    goal: Goal | Sequence[float]
    start: Sequence[float] | None = None
    arm: ArmModel | None = None
    motion: MotionProfile = field(default_factory=MotionProfile)
    angular_velocity: float = DEFAULT_OMEGA
    world: CollisionWorld | None = None
    algorithm: str = 'iepso'
    population: int = 40
    max_iterations: int = 1000
    convergence_precision: float = 1e-7
    seed: int | np.random.Generator | None = None
    shaping: RewardPunishment | None = None
    optimizer_options: Mapping[str, Any] = field(default_factory=dict)
    max_planning_time: float | None = None
    start_limit_margin: float = 0.05
    detours: bool = True

    def __post_init__(self) -> None:
        """Hold a position as a point goal (ValueError if not numbers), the start as floats."""
        if not isinstance(self.goal, Goal):
            object.__setattr__(self, 'goal', Goal(self.goal))
        if self.start is not None:
            object.__setattr__(self, 'start', np.asarray(self.start, dtype=float).ravel())

    @classmethod
    def from_keywords(cls, goal: Goal | Sequence[float], start: Sequence[float] | None = None,
                      **settings: Any) -> PlanRequest:
        """
        Return the request of ``plan``'s keywords; the names of ``RENAMED`` are taken too.

        The goal's settings (``GOAL_SETTINGS``: ``mode``, ``tolerance``, ...) given beside a
        position make its ``Goal``; ``velocity_scaling`` and ``acceleration_scaling`` set the
        motion's (``MotionProfile``).
        """
        for old, new in RENAMED.items():
            if old in settings:
                if new in settings:
                    raise TypeError(f'give {new} or its old name {old}, not both')
                settings[new] = settings.pop(old)
        if settings.get('motion') is None:
            settings.pop('motion', None)
        scaling = {k: settings.pop(k) for k in SCALING_KEYS if k in settings}
        if scaling:              # the motion's own settings, given beside it
            settings['motion'] = replace(settings.get('motion', MotionProfile()), **scaling)
        wanted = {k: settings.pop(k) for k in GOAL_SETTINGS if k in settings}
        if wanted:
            if isinstance(goal, Goal):
                raise TypeError(f"give {', '.join(sorted(wanted))} in the Goal, not beside it")
            goal = Goal(goal, **wanted)
        if settings.get('optimizer_options') is None:
            settings.pop('optimizer_options', None)
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(settings) - known)
        if unknown:
            raise TypeError(f"unknown setting(s) {', '.join(unknown)}; a plan takes "
                            f"{', '.join(sorted(known - {'goal', 'start'} | GOAL_SETTINGS))}")
        return cls(goal, start, **settings)

    @property
    def planned_arm(self) -> ArmModel:
        """Return the arm planned for: ``arm``, or the paper's when it is None."""
        return self.arm if self.arm is not None else _paper_arm()

    def replace(self, **changes: Any) -> PlanRequest:
        """Return a copy with ``changes`` (as ``dataclasses.replace``)."""
        return replace(self, **changes)

    def validate(self) -> None:
        """Raise ValueError with a one-line reason when a setting cannot be planned with."""
        if self.algorithm not in ALGORITHMS:
            raise ValueError(f'unknown algorithm {self.algorithm!r}; choose from '
                             f"{', '.join(ALGORITHMS)}")
        self.goal.validate()
        positive = {'angular_velocity': self.angular_velocity}
        if self.max_planning_time is not None:
            positive['max_planning_time'] = self.max_planning_time
        for name, value in positive.items():
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
                raise ValueError(f'{name} must be finite and positive, got {value!r}')
        for name in ('convergence_precision', 'start_limit_margin'):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value >= 0):
                raise ValueError(f'{name} must be finite and not negative, got {value!r}')
        for name, least in (('population', 2), ('max_iterations', 1)):
            value = getattr(self, name)
            if (isinstance(value, bool) or not isinstance(value, (int, np.integer))
                    or value < least):
                raise ValueError(f'{name} must be an integer of at least {least}, got {value!r}')
        if not (self.seed is None or isinstance(self.seed, np.random.Generator)
                or isinstance(self.seed, (int, np.integer)) and not isinstance(self.seed, bool)
                and self.seed >= 0):
            raise ValueError(f'seed must be None, an integer >= 0 or a numpy Generator, '
                             f'got {self.seed!r}')
        self._check_options()
        if not isinstance(self.detours, bool):
            raise ValueError(f'detours must be true or false, got {self.detours!r}')
        arm = self.planned_arm
        if self.world is not None and self.world.arm.geometry.arm.joint_names != arm.joint_names:
            raise ValueError(f'the collision model is of joints '
                             f'{self.world.arm.geometry.arm.joint_names}, the arm has '
                             f'{arm.joint_names}')
        self.motion.time_law(arm, self.angular_velocity)        # the limits it needs, or why not

    def _check_options(self) -> None:
        """Refuse an optimiser option that the algorithm does not take."""
        accepted = _options_of(self.algorithm)
        unknown = sorted(set(self.optimizer_options) - accepted)
        if unknown:
            raise ValueError(f"{self.algorithm} has no option {', '.join(unknown)}; it takes "
                             f"{', '.join(sorted(accepted)) or 'none'}")


@functools.lru_cache(maxsize=None)
def _options_of(algorithm: str) -> frozenset[str]:
    """Return the keywords of an optimiser that ``optimizer_options`` may set."""
    return frozenset(inspect.signature(ALGORITHMS[algorithm]).parameters) - _OWN_KEYWORDS - {'obj'}
