# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The benchmark's goals: seeded random reachable goals, or the paper's target.

Goals are tool positions of seeded random in-limit configurations (in radial mode only those
with a radial solution); starts are q = 0 or random in-limit configurations. Each case carries
its exact optimum (``reference.exact_minimum``) and the seed its plans get.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trajplan_ros.kinematics import ArmModel
from trajplan_ros.planning.objective import Mode
from trajplan_ros.planning.paper_experiment import PAPER_TARGET
from trajplan_ros.planning.reference import exact_minimum, ExactOptimum

__all__ = ['Case', 'draw_cases', 'paper_case']


@dataclass(frozen=True)
class Case:
    """One benchmark goal: where to go, from where, the exact optimum and the plans' seed."""

    goal: np.ndarray
    start: np.ndarray
    exact: ExactOptimum
    seed: int

    @property
    def exact_time(self) -> float:
        """Return the exact minimum motion time (s)."""
        return self.exact.motion_time_s


def draw_cases(arm: ArmModel, n: int, *, mode: Mode, random_starts: bool,
               seed: int) -> list[Case]:
    """
    Draw ``n`` goals from seeded random in-limit configurations, rejecting those with no solution.

    Each draw takes two configurations, the goal's and the start's, whether or not the start is
    used, so the goals do not depend on ``random_starts``.
    """
    rng = np.random.default_rng(seed)
    cases: list[Case] = []
    for _ in range(100 * n):
        if len(cases) == n:
            break
        q = arm.lower + (arm.upper - arm.lower) * rng.random((2, arm.n_joints))
        goal = arm.tool(q[:1])[0][0]
        start = q[1] if random_starts else np.zeros(arm.n_joints)
        plan_seed = int(rng.integers(2 ** 31))
        exact = exact_minimum(arm, goal, start, mode=mode.value)
        if np.isfinite(exact.motion_time_s):
            cases.append(Case(goal, start, exact, plan_seed))
    if len(cases) < n:
        raise ValueError(f'found only {len(cases)} of {n} goals with a {mode.value} solution')
    return cases


def paper_case(arm: ArmModel, mode: Mode, seed: int) -> Case:
    """Return the paper's experiment: its target from the upright pose q = 0."""
    start = np.zeros(arm.n_joints)
    return Case(PAPER_TARGET, start, exact_minimum(arm, PAPER_TARGET, start, mode=mode.value),
                seed)
