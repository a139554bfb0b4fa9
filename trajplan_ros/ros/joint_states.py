# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The arm's measured state from joint_states, with every problem reported, and a plan's start.

A joint_states message can be wrong in four ways: its name and position lists differ in length,
one of the arm's joints has a non-finite position or appears twice, or it names none of the
arm's joints (other joints, such as a gripper's, are not checked: they are not ours). Each kind
of problem is logged the first time it is seen; its repeats are counted and summarised at most
once per ``repeat_period`` seconds (``flush_repeats`` summarises what is left). A message with
a problem changes nothing. Nothing here
imports rclpy: the node passes the message's lists and a logging function.
"""
from __future__ import annotations

import collections
import math
import threading
import time
from typing import Callable, Mapping, Sequence

import numpy as np


__all__ = ['JointStateMonitor', 'PlanStart']

#: Problem kinds, as counted in diagnostics.
LENGTH, NON_FINITE, DUPLICATE, UNKNOWN = ('length mismatch', 'non-finite position',
                                          'duplicate name', 'no arm joint')


class PlanStart:
    """The start of a plan: joint angles, and which source each joint came from."""

    def __init__(self, names: Sequence[str], angles: Sequence[float],
                 sources: Sequence[str]) -> None:
        self.q = np.asarray(angles, dtype=float)
        self.sources = dict(zip(names, sources))

    def given(self, angles: Mapping[str, float], source: str) -> PlanStart:
        """Return this start with the joints ``angles`` names (others ignored) from ``source``."""
        names = list(self.sources)
        return PlanStart(names, [float(angles.get(n, q)) for n, q in zip(names, self.q)],
                         [source if n in angles else self.sources[n] for n in names])

    def describe(self) -> str:
        """Say where the joints came from, when there was more than one source, else ''."""
        by_source: dict[str, list[str]] = collections.defaultdict(list)
        for name, source in self.sources.items():
            by_source[source].append(name)
        if len(by_source) < 2:
            return ''
        return ' [' + '; '.join(f"{', '.join(names)} from {source}"
                                for source, names in by_source.items()) + ']'


class JointStateMonitor:
    """Keep the newest valid joint angles by name, and report what is wrong with the rest."""

    def __init__(self, warn: Callable[[str], None], repeat_period: float = 5.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self._warn, self._period, self._clock = warn, repeat_period, clock
        self._lock = threading.Lock()
        self._updated = threading.Condition(self._lock)
        self._measured: dict[str, float] = {}
        self._last_end: dict[str, float] = {}
        #: problem kind -> how many messages had it
        self.problems: collections.Counter[str] = collections.Counter()
        #: problem kind -> [repeats not yet logged, time of the last log line, latest text]
        self._repeats: dict[str, list] = {}

    def update(self, names: Sequence[str], positions: Sequence[float],
               arm_joints: Sequence[str]) -> None:
        """Take one joint_states message (its name and position lists)."""
        if not positions:
            return                              # velocities or efforts only: nothing to take
        problem = self._problem(list(names), list(positions), arm_joints)
        if problem is not None:
            self._report(*problem)
            return
        ours = set(arm_joints)
        with self._lock:
            self._measured.update({n: float(q) for n, q in zip(names, positions) if n in ours})
            self._updated.notify_all()

    def forget(self) -> None:
        """Drop every known joint angle (the arm changed: names may now mean other joints)."""
        with self._lock:
            self._measured.clear()
            self._last_end.clear()

    def trajectory_ended(self, names: Sequence[str], angles: Sequence[float]) -> None:
        """Remember where the last published trajectory ends."""
        with self._lock:
            self._last_end = dict(zip(names, map(float, angles)))

    def measured(self, names: Sequence[str]) -> dict[str, float]:
        """Return the newest joint_states angle of each of ``names`` that has one."""
        with self._lock:
            return {name: self._measured[name] for name in names if name in self._measured}

    def wait_for(self, names: Sequence[str], timeout: float) -> bool:
        """Wait up to ``timeout`` s until every one of ``names`` has an angle; True if so."""
        with self._updated:
            return self._updated.wait_for(lambda: all(n in self._measured for n in names),
                                          timeout)

    def start(self, names: Sequence[str], defaults: Sequence[float]) -> PlanStart:
        """Per joint: joint_states, else the last trajectory's end, else ``defaults``."""
        with self._lock:
            measured, last_end = dict(self._measured), dict(self._last_end)
        angles, sources = [], []
        for name, default in zip(names, defaults):
            for source, known in (('joint_states', measured), ('trajectory end', last_end),
                                  ('start_positions', {name: default})):
                if name in known:
                    angles.append(known[name])
                    sources.append(source)
                    break
        return PlanStart(names, angles, sources)

    @staticmethod
    def _problem(names: list[str], positions: list[float],
                 arm_joints: Sequence[str]) -> tuple[str, str] | None:
        """Return (kind, text) of what is wrong with a message, or None."""
        if len(names) != len(positions):
            return LENGTH, f'{len(names)} names but {len(positions)} positions'
        ours = set(arm_joints)
        seen = collections.Counter(n for n in names if n in ours)
        if not seen:
            return UNKNOWN, (f"names none of the arm's joints: got {', '.join(names)}; "
                             f"expected {', '.join(arm_joints)}")
        twice = sorted(n for n, k in seen.items() if k > 1)
        if twice:
            return DUPLICATE, f"duplicate name {', '.join(twice)}"
        bad = [n for n, q in zip(names, positions) if n in ours and not math.isfinite(q)]
        if bad:
            return NON_FINITE, f"non-finite position for {', '.join(bad)}"
        return None

    def _report(self, kind: str, text: str) -> None:
        """Log a kind of problem at once the first time, its repeats at most once a period."""
        now = self._clock()
        with self._lock:
            self.problems[kind] += 1
            entry = self._repeats.get(kind)
            if entry is None:
                self._repeats[kind] = [0, now, text]
                message = f'ignored joint_states: {text}'
            else:
                entry[0] += 1
                entry[2] = text
                message = self._summary(kind, now)
        if message:
            self._warn(message)

    def _summary(self, kind: str, now: float) -> str | None:
        """Return the summary line of ``kind``'s repeats if its period is over (lock held)."""
        count, last, text = self._repeats[kind]
        if not count or now - last < self._period:
            return None
        self._repeats[kind][:2] = [0, now]
        return (f'ignored joint_states: {text} (again, {count:g} times in the last '
                f'{now - last:.0f} s)')

    def flush_repeats(self) -> None:
        """Log the summaries whose period is over (call it now and then, e.g. from a timer)."""
        now = self._clock()
        with self._lock:
            messages = [self._summary(kind, now) for kind in list(self._repeats)]
        for message in filter(None, messages):
            self._warn(message)

    def counts(self) -> Mapping[str, int]:
        """Messages ignored so far, by problem kind (every kind listed)."""
        with self._lock:
            return {kind: self.problems[kind] for kind in (LENGTH, NON_FINITE, DUPLICATE, UNKNOWN)}
