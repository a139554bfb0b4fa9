# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Run the benchmark: every method on every case, taking turns goal by goal.

Time per plan is the wall time of the ``plan`` (or peer) call, including the construction of the
objective, measured with ``time.perf_counter``; the methods take turns goal by goal, so a busy
machine slows them alike. Every answer is scored on the same objective F, the default one (with
the reward). A plan succeeds when its position error is at most 1 um, in radial mode its tool
axis is within 1e-6 rad of the goal ray, and its motion time is within 0.1 % of the exact minimum
(``reference.exact_minimum``). On a goal with no solution (``cases.draw_cases`` with
``only="no-solution"``) success is the reverse: the answer is not reached, and a plan does not
claim it.
"""
from __future__ import annotations

from dataclasses import dataclass
import time
from typing import Callable, Sequence

import numpy as np

from trajplan_ros.kinematics import ArmModel
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.planning.planner import PlanResult
from trajplan_ros.search.goal import Goal, Mode
from trajplan_ros.search.objective import Objective
from trajplan_ros.tools.bench.cases import Case
from trajplan_ros.tools.bench.methods import Answer, Method

__all__ = ['Results', 'run', 'SUCCESS_AXIS_ERROR', 'SUCCESS_ERROR', 'SUCCESS_GAP']

#: Success: position error at most this (m) ...
SUCCESS_ERROR = 1e-6
#: ... in radial mode, the tool axis at most this far from the goal ray (rad) ...
SUCCESS_AXIS_ERROR = 1e-6
#: ... and motion time at most this fraction above the exact minimum.
SUCCESS_GAP = 1e-3


@dataclass
class Results:
    """One method's outcome on every case (arrays indexed by case)."""

    x: np.ndarray              # (n, planned) joint goals, rad
    efficiency: np.ndarray     # F under the default objective (with reward), s
    error: np.ndarray          # position error, m
    axis_error: np.ndarray     # angle of the tool axis to the goal ray, rad (radial mode; else 0)
    motion_time: np.ndarray    # R, s
    gap: np.ndarray            # R / exact minimum - 1 (NaN where the goal has no solution)
    seconds: np.ndarray        # wall time per plan, s
    claimed: np.ndarray        # the plan said SUCCEEDED (peers: reached, by the same test)
    plans: list[PlanResult | None]

    @classmethod
    def empty(cls, n: int, planned: int) -> Results:
        """Return results for ``n`` cases, all NaN until ``run`` fills them in."""
        return cls(np.full((n, planned), np.nan), *(np.full(n, np.nan) for _ in range(6)),
                   np.zeros(n, dtype=bool), [None] * n)

    @property
    def reached(self) -> np.ndarray:
        """Tell for each case whether the answer meets the goal (and the ray, in radial mode)."""
        return (self.error <= SUCCESS_ERROR) & (self.axis_error <= SUCCESS_AXIS_ERROR)

    @property
    def success(self) -> np.ndarray:
        """
        Tell for each case whether the plan reached the goal in the least time.

        Where the goal has no solution (gap NaN): whether neither the answer nor the plan
        claims it is reached.
        """
        solvable = ~np.isnan(self.gap)
        return np.where(solvable, self.reached & (self.gap <= SUCCESS_GAP),
                        ~self.reached & ~self.claimed)


def _score(res: Results, k: int, obj: Objective, answer: Answer, case: Case) -> None:
    """Fill in row k of ``res`` for ``answer`` to ``case``, scored on ``obj``."""
    x = np.atleast_2d(answer.x)
    ev = obj(x)
    tool = obj.tool(x)
    res.x[k], res.plans[k] = answer.x, answer.plan
    res.efficiency[k], res.motion_time[k] = ev.efficiency[0], ev.motion_time[0]
    res.error[k] = np.linalg.norm(tool[0, 0] - obj.goal)
    res.axis_error[k] = obj.angle_errors(tool)[0] if obj.holds_axis else 0.0
    exact = case.exact_time
    res.gap[k] = ev.motion_time[0] / exact - 1.0 if np.isfinite(exact) else np.nan
    res.claimed[k] = (answer.plan.success if answer.plan is not None
                      else bool(res.reached[k]))


def run(methods: Sequence[Method], cases: Sequence[Case], arm: ArmModel, mode: Mode,
        step: Callable[[], object] | None = None,
        profile: MotionProfile | None = None) -> dict[str, Results]:
    """
    Run every method on every case, taking turns goal by goal; score the answers on the same F.

    ``profile``: the motion's profile and limits, for the plans and their scores.

    ``step``, when given, is called after each case (a progress bar's ``update``).
    """
    out = {m.name: Results.empty(len(cases), arm.planned) for m in methods}
    for k, case in enumerate(cases):
        obj = Objective(arm, Goal(case.goal, mode=mode), case.start, profile=profile)
        for method in methods:
            clock = time.perf_counter()
            answer = method.solve(arm, mode, case.goal, case.start, case.seed, obj.profile)
            seconds = time.perf_counter() - clock
            _score(out[method.name], k, obj, answer, case)
            out[method.name].seconds[k] = seconds if answer.seconds is None else answer.seconds
        if step is not None:
            step()
    return out
