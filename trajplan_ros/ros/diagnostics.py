# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The planner node's counters, and their diagnostic_msgs/DiagnosticArray form.

The node publishes the array on ``/diagnostics`` once a second, as diagnostic_updater nodes do,
so rqt_robot_monitor shows the planner. Every goal the node receives ends in exactly one of
planned (published), superseded (a newer goal replaced it while it waited) or failed (refused,
not reached, timed out, or unplanned at shutdown); every call received is answered once.
"""
from __future__ import annotations

import collections
import threading
from typing import Mapping

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
import numpy as np
from std_msgs.msg import Header


__all__ = ['Counters', 'diagnostic_array']

#: A call waiting longer than this (s) turns the status to WARN.
SLOW_CALL_S = 1.0
#: Plan times kept for the p99.
PLAN_TIMES = 1000


class Counters:
    """Thread-safe counts of goals and calls, and recent plan times."""

    FIELDS = ('goals_received', 'goals_planned', 'goals_superseded', 'goals_failed',
              'calls_received', 'calls_answered', 'plans_timed_out')

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._counts = dict.fromkeys(self.FIELDS, 0)
        self._plan_times: collections.deque[float] = collections.deque(maxlen=PLAN_TIMES)
        self._superseded_reported = 0

    def add(self, name: str, amount: int = 1) -> None:
        """Count ``amount`` more of ``name`` (one of ``FIELDS``)."""
        with self._lock:
            self._counts[name] += amount

    def plan_time(self, seconds: float) -> None:
        """Record how long a plan took."""
        with self._lock:
            self._plan_times.append(seconds)

    def snapshot(self) -> dict[str, float]:
        """Return the counts, the last and p99 plan time (s, NaN before the first plan)."""
        with self._lock:
            out: dict[str, float] = dict(self._counts)
            times = list(self._plan_times)
        out['last_plan_time_s'] = times[-1] if times else float('nan')
        out['p99_plan_time_s'] = float(np.percentile(times, 99)) if times else float('nan')
        return out

    def superseded_since_last_report(self) -> int:
        """Return the goals superseded since the last call of this method."""
        with self._lock:
            new = self._counts['goals_superseded'] - self._superseded_reported
            self._superseded_reported = self._counts['goals_superseded']
            return new


def diagnostic_array(name: str, header: Header, counts: Mapping[str, float], waiting: int,
                     oldest_wait_s: float, superseded_now: int,
                     joint_state_problems: Mapping[str, int]) -> DiagnosticArray:
    """Build the node's DiagnosticArray: one status, WARN when calls wait long or goals drop."""
    problems = []
    if oldest_wait_s > SLOW_CALL_S:
        problems.append(f'a call has waited {oldest_wait_s:.1f} s')
    if superseded_now:
        problems.append(f'{superseded_now} goal(s) superseded in the last second')
    level = DiagnosticStatus.WARN if problems else DiagnosticStatus.OK
    values = {**counts, 'calls_waiting': waiting, 'oldest_call_wait_s': oldest_wait_s}
    values.update({f'joint_states {kind}': n for kind, n in joint_state_problems.items()})
    status = DiagnosticStatus(
        level=level, name=f'{name}: planner', hardware_id='',
        message='; '.join(problems) if problems else 'planning',
        values=[KeyValue(key=k, value=f'{v:g}' if isinstance(v, float) else str(v))
                for k, v in values.items()])
    return DiagnosticArray(header=header, status=[status])
