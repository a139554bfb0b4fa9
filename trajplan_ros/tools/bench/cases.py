# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The benchmark's goals: seeded random reachable goals, or the paper's target.

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

import numpy as np

from trajplan_ros.kinematics import ArmModel
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.search.objective import Mode
from trajplan_ros.tools.bench.paper_experiment import PAPER_TARGET
from trajplan_ros.tools.bench.reference import exact_minimum, ExactOptimum

__all__ = ['Case', 'DRAWS', 'draw_cases', 'paper_case']

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
