# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
``PlanRequest``: everything one plan needs, under the names users know, and its checking.

The goal and start, the arm, the mode, the motion's profile and the collision world; the
search's settings (algorithm, swarm size, iteration cap, convergence precision, seed, fuzzy
shaping, optimiser options); the limits on its work (``max_planning_time``). The names are the
node's parameters and the ``trajplan plan`` flags: ``angular_velocity`` (``--angular-velocity``),
``max_iterations``, ``tolerance``, ``axis_tolerance``, ``orientation_tolerance``,
``max_planning_time``.

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
from trajplan_ros.search.iepso import iepso
from trajplan_ros.search.objective import DEFAULT_OMEGA, Mode, TOP_DOWN, unit_direction
from trajplan_ros.search.optimize import OptimizeResult

__all__ = ['ALGORITHMS', 'DEFAULT_AXIS_TOLERANCE', 'DEFAULT_ORIENTATION_TOLERANCE',
           'DEFAULT_TOLERANCE', 'PlanRequest', 'RENAMED']

#: Name -> optimiser; every one takes (objective, population=, max_iter=, tol=, seed=).
ALGORITHMS: dict[str, Callable[..., OptimizeResult]] = {
    'iepso': iepso, 'pso': pso, 'spso': spso, 'ga': ga, 'de': de,
}
#: Largest error (m) that counts as reached unless the caller says otherwise.
DEFAULT_TOLERANCE = 1e-6
#: Largest angle (rad) between the tool axis and its target that counts as met, by mode: the
#: goal ray of the paper's radial mode is met exactly; an approach direction within 1 mrad,
#: as a small arm's URDF axes, off by micro-radians, often cannot point exactly along it.
DEFAULT_AXIS_TOLERANCE = MappingProxyType({Mode.RADIAL.value: 1e-6, Mode.APPROACH.value: 1e-3})
#: Largest angle (rad) of the rotation between a pose's goal orientation and the reached one
#: that counts as met: a six- or seven-joint arm meets a pose exactly.
DEFAULT_ORIENTATION_TOLERANCE = 1e-6
#: Earlier keyword names of ``plan`` -> the request's names (the old ones keep working).
RENAMED = MappingProxyType({'omega': 'angular_velocity', 'max_iter': 'max_iterations',
                            'tol': 'convergence_precision', 'profile': 'motion',
                            'options': 'optimizer_options'})
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

    :param goal: tool position (x, y, z), m, in the arm's base frame.
    :param start: all joint angles now (rad); None: the upright pose q = 0.
    :param arm: the arm model; None: the paper's arm.
    :param mode: "free" (position only), "radial" (eq. 12-13: the tool axis along the goal
        ray, pointing outward, too), "approach" (the tool axis along ``approach``) or "pose"
        (the tool frame's whole orientation is ``orientation``).
    :param approach: approach mode: the direction the tool axis points along (base frame; need
        not be a unit vector); the default (0, 0, -1) is a grasp from above.
    :param orientation: pose mode: the tool (tip) frame's orientation in the base frame, a
        unit quaternion (x, y, z, w).
    :param joint_goal: a joint goal instead: every joint's angle (rad), or the planned ones
        (the others keep their start); the plan is the motion there, direct or, with a
        ``world`` and ``detours``, through via points. ``goal`` is then not read (give ()),
        nor the mode's orientation settings.
    :param motion: the motion's profile, timing and limits; the plan minimises its duration.
    :param angular_velocity: the servo angular velocity omega of eq. (10), rad/s; it caps every
        joint's velocity.
    :param world: the arm's collision model, scene and padding: the plan is the fastest direct
        motion found that keeps the padding. None: no collision check.
    :param tolerance: largest position error (m). The tolerances make the goal a region: the
        plan is the fastest motion found to any point, axis or orientation within them
        (``search.region``); at 1e-6 or less they are the goal itself.
    :param axis_tolerance: radial and approach modes: largest angle (rad) of the tool axis to
        the goal ray or the approach direction; None: the mode's ``DEFAULT_AXIS_TOLERANCE``.
    :param orientation_tolerance: pose mode: largest angle (rad) of the rotation between the
        goal orientation and the reached one.
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

    goal: Sequence[float]
    start: Sequence[float] | None = None
    arm: ArmModel | None = None
    mode: Mode | str = Mode.FREE
    approach: Sequence[float] = TOP_DOWN
    orientation: Sequence[float] | None = None
    joint_goal: Sequence[float] | None = None
    motion: MotionProfile = field(default_factory=MotionProfile)
    angular_velocity: float = DEFAULT_OMEGA
    world: CollisionWorld | None = None
    tolerance: float = DEFAULT_TOLERANCE
    axis_tolerance: float | None = None
    orientation_tolerance: float = DEFAULT_ORIENTATION_TOLERANCE
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
        """Hold the goal as floats (ValueError if it is not numbers) and the mode as a Mode."""
        object.__setattr__(self, 'goal', np.asarray(self.goal, dtype=float).ravel())
        for name in ('start', 'joint_goal'):
            if getattr(self, name) is not None:
                value = np.asarray(getattr(self, name), dtype=float).ravel()
                object.__setattr__(self, name, value)
        if self.mode not in tuple(Mode) + tuple(m.value for m in Mode):
            raise ValueError(f"mode must be one of {', '.join(m.value for m in Mode)}, "
                             f'got {self.mode!r}')
        object.__setattr__(self, 'mode', Mode(self.mode))
        object.__setattr__(self, 'approach', tuple(float(v) for v in np.ravel(self.approach)))
        if self.orientation is not None:
            object.__setattr__(self, 'orientation',
                               tuple(float(v) for v in np.ravel(self.orientation)))

    @classmethod
    def from_keywords(cls, goal: Sequence[float], start: Sequence[float] | None = None,
                      **settings: Any) -> PlanRequest:
        """
        Return the request of ``plan``'s keywords; the names of ``RENAMED`` are taken too.

        ``velocity_scaling`` and ``acceleration_scaling`` set the motion's (``MotionProfile``).
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
        if settings.get('optimizer_options') is None:
            settings.pop('optimizer_options', None)
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(settings) - known)
        if unknown:
            raise TypeError(f"unknown setting(s) {', '.join(unknown)}; a plan takes "
                            f"{', '.join(sorted(known - {'goal', 'start'}))}")
        return cls(goal, start, **settings)

    @property
    def planned_arm(self) -> ArmModel:
        """Return the arm planned for: ``arm``, or the paper's when it is None."""
        return self.arm if self.arm is not None else _paper_arm()

    @property
    def angle_limit(self) -> float:
        """Return the largest angle error that counts as met: the pose's, or ``axis_limit``."""
        return self.orientation_tolerance if self.mode is Mode.POSE else self.axis_limit

    @property
    def axis_limit(self) -> float:
        """Return the axis tolerance in force: ``axis_tolerance``, or the mode's default."""
        if self.axis_tolerance is not None:
            return self.axis_tolerance
        return DEFAULT_AXIS_TOLERANCE.get(self.mode.value, DEFAULT_AXIS_TOLERANCE['radial'])

    def replace(self, **changes: Any) -> PlanRequest:
        """Return a copy with ``changes`` (as ``dataclasses.replace``)."""
        return replace(self, **changes)

    def validate(self) -> None:
        """Raise ValueError with a one-line reason when a setting cannot be planned with."""
        if self.algorithm not in ALGORITHMS:
            raise ValueError(f'unknown algorithm {self.algorithm!r}; choose from '
                             f"{', '.join(ALGORITHMS)}")
        positive = {'angular_velocity': self.angular_velocity, 'tolerance': self.tolerance,
                    'axis_tolerance': self.axis_limit,
                    'orientation_tolerance': self.orientation_tolerance}
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
        unit_direction(self.approach)
        if self.orientation is not None and self.mode is not Mode.POSE:
            raise ValueError(f'an orientation is for pose mode, not {self.mode.value}')
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
