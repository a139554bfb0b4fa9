# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The benchmark's cases: the paper's experiment, published arms, and goals to plan.

The paper's target and Table 5 as printed (``PAPER_TARGET``, ``PAPER_TABLE5``). The published
arm URDFs that the bench and the tests plan for (``PUBLISHED``), from the example-robot-data
wheel: the vendors' own files (with their warts: xacro leftovers in names, grippers on side
branches, ``package://`` meshes), nothing copied or edited, each entry naming the chain the
bench uses: base link, tip link and how many revolute joints lie between.

Goals are tool positions of seeded random in-limit configurations (in radial mode only those
with a radial solution); starts are q = 0 or random in-limit configurations. Each case carries
its exact optimum (``reference.exact_minimum``) and the seed its plans get. Two kinds of goals
can be drawn alone (``DRAWS``):

* "limit-optima": goals whose exact optimum has a joint on a limit. Their configurations have
  one planned joint pinned to a limit (in radial mode, the other joints then turned so that the
  tool axis lies on the goal ray), and a goal is kept when its exact optimum lies on a limit;
* "no-solution": goals without a solution: in radial mode reachable goals with no radial pose,
  in free mode points drawn uniformly in the reach sphere of eq. (14) that no pose reaches.
"""
from __future__ import annotations

from dataclasses import dataclass
import importlib.metadata
from pathlib import Path

import numpy as np

from trajplan_ros.kinematics import ArmModel
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.search.goal import Mode
from trajplan_ros.tools.bench.reference import exact_minimum, ExactOptimum

__all__ = ['Case', 'DRAWS', 'PAPER_TABLE5', 'PAPER_TARGET', 'PUBLISHED', 'PublishedArm',
           'draw_cases', 'paper_case', 'robots_dir']

#: The target of section VI.B, m (the paper's (151.171, 191.62, 172.124) mm), reached from the
#: upright pose q = 0.
PAPER_TARGET = np.array([0.151171, 0.19162, 0.172124])
PAPER_TARGET.flags.writeable = False

#: Table 5 as printed: algorithm -> (q1..q4 in rad, efficiency scalar F, error in mm).
PAPER_TABLE5: dict[str, tuple[tuple[float, ...], float, float]] = {
    'pso': ((-2.24, -1.31, 1.06, -1.11), 8.71e4, 10.41),
    'spso': ((0.89, 0.12, 1.47, -0.67), 5.52e2, 5.46),
    'iepso': ((0.9, 1.49, -0.23, 1.17), -16.56, 6.96e-14),
    'ga': ((0.9, 0.92, 0.84, -1.54), -3.59, 3.06e-4),
    'de': ((0.9, 0.09, 1.13, -0.09), -2.57, 0.12),
}


@dataclass(frozen=True)
class PublishedArm:
    """One arm: its URDF below ``robots_dir()``, the chain from ``base_link`` to ``tip_link``."""

    path: str
    base_link: str
    tip_link: str
    joints: int

    @property
    def urdf(self) -> Path:
        """Return the URDF file's path."""
        return robots_dir() / self.path


PUBLISHED = {
    'so101': PublishedArm('so_arm_description/urdf/so101.urdf', 'base_link',
                          'gripper_frame_link', 5),
    'ur5': PublishedArm('ur_description/urdf/ur5_robot.urdf', 'base_link', 'tool0', 6),
    'xarm7': PublishedArm('xarm_description/urdf/xarm7.urdf', 'link_base', 'link_eef', 7),
    'panda': PublishedArm('panda_description/urdf/panda.urdf', 'panda_link0', 'panda_hand_tcp',
                          7),
    'kinova': PublishedArm('kinova_description/robots/kinova.urdf', 'base',
                           'j2s6s200_end_effector', 6),
}


def robots_dir() -> Path:
    """Return the example-robot-data robots folder (the wheel is a test and bench extra)."""
    try:
        dist = importlib.metadata.distribution('example-robot-data')
    except importlib.metadata.PackageNotFoundError:
        raise FileNotFoundError('example-robot-data is not installed: '
                                "pip install '.[bench]'") from None
    return Path(dist.locate_file('cmeel.prefix/share/example-robot-data/robots'))


#: The kinds of goals ``draw_cases`` draws.
DRAWS = ('all', 'limit-optima', 'no-solution')


@dataclass(frozen=True)
class Case:
    """One benchmark goal: where to go, from where, the exact optimum and the plans' seed."""

    goal: np.ndarray
    start: np.ndarray
    exact: ExactOptimum
    seed: int
    #: The seed of the set the case was drawn in (``draw_cases``).
    draw_seed: int = 0

    @property
    def exact_time(self) -> float:
        """Return the exact minimum motion time (s)."""
        return self.exact.motion_time_s


def _pinned(arm: ArmModel, q: np.ndarray, mode: Mode, rng: np.random.Generator) -> np.ndarray:
    """
    Return q with a random planned joint on a random one of its limits.

    In radial mode the other planned joints are then solved (scipy's least_squares, within the
    limits) so that the tool axis lies on the goal ray; NaN when that fails.
    """
    from scipy.optimize import least_squares

    q = q.copy()
    j = int(rng.integers(arm.planned))
    q[j] = arm.upper[j] if rng.random() < 0.5 else arm.lower[j]
    if mode is not Mode.RADIAL:
        return q
    others = np.array([i for i in range(arm.planned) if i != j])

    def off_ray(x: np.ndarray) -> np.ndarray:
        trial = q.copy()
        trial[others] = x
        p, u = arm.tool(trial[None, :])
        return u[0] - p[0] / np.linalg.norm(p[0])

    found = least_squares(off_ray, q[others], bounds=(arm.lower[others], arm.upper[others]),
                          xtol=1e-15, ftol=1e-15, gtol=1e-15)
    q[others] = found.x
    return q if np.linalg.norm(off_ray(found.x)) < 1e-12 else np.full_like(q, np.nan)


def _on_limit(arm: ArmModel, exact: ExactOptimum) -> bool:
    """Tell whether the exact optimum has a planned joint on a limit (within 1e-7 rad)."""
    q, m = exact.joint_goal, arm.planned
    return bool(np.any(np.minimum(np.abs(q - arm.lower[:m]), np.abs(q - arm.upper[:m])) < 1e-7))


def _goal(arm: ArmModel, q: np.ndarray, mode: Mode, only: str,
          rng: np.random.Generator) -> np.ndarray:
    """Return a goal of the kind ``only`` asks for, from the configuration q (NaN: none)."""
    if only == 'no-solution' and mode is Mode.FREE:
        direction = rng.normal(size=3)
        return arm.reach * rng.random() ** (1 / 3) * direction / np.linalg.norm(direction)
    if only == 'limit-optima':
        q = _pinned(arm, q, mode, rng)
    return arm.tool(q[None, :])[0][0]


def draw_cases(arm: ArmModel, n: int, *, mode: Mode, random_starts: bool, seed: int,
               only: str = 'all', profile: MotionProfile | None = None) -> list[Case]:
    """
    Draw ``n`` goals of the kind ``only`` (``DRAWS``; see the module docstring).

    For "all", goals come from seeded random in-limit configurations, rejecting those with no
    solution. Each draw takes two configurations, the goal's and the start's, whether or not the
    start is used, so the goals do not depend on ``random_starts``.
    """
    if only not in DRAWS:
        raise ValueError(f"only must be one of {', '.join(DRAWS)}, got {only!r}")
    rng = np.random.default_rng(seed)
    cases: list[Case] = []
    for _ in range(1000 * n):
        if len(cases) == n:
            break
        q = arm.lower + (arm.upper - arm.lower) * rng.random((2, arm.n_joints))
        goal = _goal(arm, q[0], mode, only, rng)
        start = q[1] if random_starts else np.zeros(arm.n_joints)
        plan_seed = int(rng.integers(2 ** 31))
        if not np.all(np.isfinite(goal)):
            continue
        exact = exact_minimum(arm, goal, start, mode=mode.value, profile=profile)
        solved = np.isfinite(exact.motion_time_s)
        if (only == 'no-solution') != solved and (only != 'limit-optima' or _on_limit(arm, exact)):
            cases.append(Case(goal, start, exact, plan_seed, seed))
    if len(cases) < n:
        raise ValueError(f'found only {len(cases)} of {n} goals of the kind {only!r} in '
                         f'{mode.value} mode')
    return cases


def paper_case(arm: ArmModel, mode: Mode, seed: int,
               profile: MotionProfile | None = None) -> Case:
    """Return the paper's experiment: its target from the upright pose q = 0."""
    start = np.zeros(arm.n_joints)
    exact = exact_minimum(arm, PAPER_TARGET, start, mode=mode.value, profile=profile)
    return Case(PAPER_TARGET, start, exact, seed)
