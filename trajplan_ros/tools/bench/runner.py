# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Run the benchmark: every method on every case, taking turns goal by goal.

Time per plan is the wall time of the ``plan`` (or peer) call, including the construction of the
objective, measured with ``time.perf_counter``; the methods take turns goal by goal, so a busy
machine slows them alike. Every answer is scored on the same objective F, the default one (with
the reward). A plan succeeds when its constraint error is at most 1 um and its motion time is
within 0.1 % of the exact minimum (``reference.exact_minimum``).
"""
from __future__ import annotations

from dataclasses import dataclass
import time
from typing import Callable, Sequence

import numpy as np

from trajplan_ros.kinematics import ArmModel
from trajplan_ros.planning.objective import Mode, Objective
from trajplan_ros.planning.planner import PlanResult
from trajplan_ros.tools.bench.cases import Case
from trajplan_ros.tools.bench.methods import Method

__all__ = ['Results', 'run', 'SUCCESS_ERROR', 'SUCCESS_GAP']

#: Success: constraint error at most this (m) ...
SUCCESS_ERROR = 1e-6
#: ... and motion time at most this fraction above the exact minimum.
SUCCESS_GAP = 1e-3


@dataclass
class Results:
    """One method's outcome on every case (arrays indexed by case)."""

    x: np.ndarray              # (n, planned) joint goals, rad
    efficiency: np.ndarray     # F under the default objective (with reward), s
    error: np.ndarray          # constraint error, m
    motion_time: np.ndarray    # R, s
    gap: np.ndarray            # R / exact minimum - 1
    seconds: np.ndarray        # wall time per plan, s
    plans: list[PlanResult | None]

    @classmethod
    def empty(cls, n: int, planned: int) -> Results:
        """Return results for ``n`` cases, all NaN until ``run`` fills them in."""
        return cls(np.full((n, planned), np.nan), *(np.full(n, np.nan) for _ in range(5)),
                   [None] * n)

    @property
    def success(self) -> np.ndarray:
        """Tell for each case whether the plan reached the goal in the least time."""
        return (self.error <= SUCCESS_ERROR) & (self.gap <= SUCCESS_GAP)


def run(methods: Sequence[Method], cases: Sequence[Case], arm: ArmModel, mode: Mode,
        step: Callable[[], object] | None = None) -> dict[str, Results]:
    """
    Run every method on every case, taking turns goal by goal; score the answers on the same F.

    ``step``, when given, is called after each case (a progress bar's ``update``).
    """
    out = {m.name: Results.empty(len(cases), arm.planned) for m in methods}
    for k, case in enumerate(cases):
        obj = Objective(arm, case.goal, case.start, mode=mode)
        for method in methods:
            clock = time.perf_counter()
            answer = method.solve(arm, mode, case.goal, case.start, case.seed)
            seconds = time.perf_counter() - clock
            ev = obj(answer.x)
            res = out[method.name]
            res.x[k], res.seconds[k], res.plans[k] = answer.x, seconds, answer.plan
            res.efficiency[k], res.error[k] = ev.efficiency[0], ev.error[0]
            res.motion_time[k] = ev.motion_time[0]
            res.gap[k] = ev.motion_time[0] / case.exact_time - 1.0
        if step is not None:
            step()
    return out
