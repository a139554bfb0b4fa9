# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Motions through via points: where no direct motion to the goal is free, the fastest found.

Not part of the paper. The motion is start -> v -> joint goal, each segment a direct motion
under the plan's profile and timing from rest to rest, so each keeps the padding along its
whole length by the same continuous check as a direct motion (``free_motion.check_motion``).
Its duration is the sum of the segments' (eq. 10 for each). The joint goal is free among the
goal's solutions (``free_goal``'s candidates, fastest first) and v among joint vectors drawn
inside the limits (the held joints at their start). Pairs (v, joint goal) are checked in the
order of their duration, each segment once; the first free pair is then pulled towards the
midpoint of its direct motion by bisection, each step kept where both segments stay free and
the motion gets shorter. Where no pair is free within ``CHECKS`` segments, two via points: a
from the via points the start reaches freely, b from those that reach a joint goal freely,
joined by a third free segment (``_two_vias``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from trajplan_ros.collision.distances import CollisionWorld
from trajplan_ros.collision.free_motion import check_motion, Clearance, StartLimits
from trajplan_ros.motion.motion_profile import Timing
from trajplan_ros.motion.time_law import motion_times, TimeLaw
from trajplan_ros.search.objective import Objective

__all__ = ['Detour', 'detour']

#: Via points drawn inside the limits.
VIAS = 96
#: Joint goals tried, fastest first.
GOALS = 6
#: Most segments checked before the search gives up.
CHECKS = 240
#: Bisection steps towards the direct motion's midpoint.
BISECTIONS = 5


@dataclass(frozen=True)
class Detour:
    """A motion through via points: its joint goal, the via points, how it keeps clear."""

    x: np.ndarray                        # the joint goal, planned joints
    vias: tuple[np.ndarray, ...]         # every joint's angles at each via point
    clearance: Clearance                 # the least clearance over the segments
    duration: float                      # s, the segments' durations summed
    checked: int                         # segments checked


def detour(obj: Objective, world: CollisionWorld, law: TimeLaw, timing: Timing,
           goals: np.ndarray, rng: np.random.Generator,
           stop: Callable[[], object] | None = None) -> Detour | None:
    """
    Return the fastest motion start -> v -> joint goal found with both segments free, or None.

    ``goals`` (K, planned): the goal's reached joint solutions, fastest first (of which the
    first ``GOALS`` whose pose is itself clear are tried); ``law``: the
    whole arm's time law; ``stop``: asked before every check, anything but None ends the search
    with what it has. See the module docstring.
    """
    check = _Checker(obj, world, law, timing, stop)
    goals = np.array([g for g in goals[:4 * GOALS] if check.segment(g, g).free][:GOALS])
    if not len(goals):                       # every joint goal found is itself in collision
        return None
    start = obj.planned_start
    vias = _vias(obj, goals, rng)
    first = _durations(obj, vias, start[None, :])[:, 0]                    # (V,)
    second = _durations(obj, vias, goals)                                   # (V, G)
    order = np.argsort((first[:, None] + second).ravel(), kind='stable')
    for flat in order:
        if check.spent(CHECKS):
            break
        v, g = divmod(int(flat), len(goals))
        found = check.through(vias[v], goals[g])
        if found is not None:
            return _pulled(obj, check, found)
    return _two_vias(obj, check, vias, goals, first, second)


def _two_vias(obj: Objective, check: _Checker, vias: np.ndarray, goals: np.ndarray,
              first: np.ndarray, second: np.ndarray) -> Detour | None:
    """
    Return the fastest motion start -> a -> b -> joint goal found, all three segments free.

    a among the via points the start reaches freely (checked already), b among those from
    which the fastest joint goals are reached freely (each checked once, fastest first), the
    pairs in the order of their duration; at most ``CHECKS`` more segments.
    """
    budget = check.count + CHECKS
    reached = [v for v in range(len(vias)) if check.known(obj.planned_start, vias[v])]
    if not reached:
        return None
    for g in range(len(goals)):
        onward = []
        for v in np.argsort(second[:, g], kind='stable'):
            if check.spent(budget) or len(onward) >= 8:
                break
            if check.segment(vias[v], goals[g]).free:
                onward.append(int(v))
        between = _durations(obj, vias[reached], vias[onward])
        total = first[reached][:, None] + between + second[onward, g][None, :]
        for flat in np.argsort(total.ravel(), kind='stable'):
            if check.spent(budget):
                return None
            a, b = divmod(int(flat), len(onward))
            if check.segment(vias[reached[a]], vias[onward[b]]).free:
                return check.through_both(vias[reached[a]], vias[onward[b]], goals[g])
    return None


def _vias(obj: Objective, goals: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """
    Return ``VIAS`` via points: half drawn inside the limits, half around direct motions.

    Those around a direct motion are its midpoint (start to one of the goals) moved by normal
    noise of a scale drawn log-uniformly from 0.3 to 1.5 rad, clipped into the limits: a short
    way around an obstacle leaves the direct motion a little.
    """
    drawn = rng.uniform(obj.lower, obj.upper, (VIAS - VIAS // 2, obj.arm.planned))
    middles = 0.5 * (obj.planned_start + goals[rng.integers(len(goals), size=VIAS // 2)])
    scale = np.exp(rng.uniform(np.log(0.3), np.log(1.5), (VIAS // 2, 1)))
    near = np.clip(middles + scale * rng.standard_normal(middles.shape), obj.lower, obj.upper)
    return np.vstack((near, drawn))


def _durations(obj: Objective, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Return the direct motions' durations from each row of a to each row of b, (A, B)."""
    moved = np.abs(a[:, None, :] - b[None, :, :]).reshape(-1, a.shape[1])
    return motion_times(obj.law, np.ascontiguousarray(moved),
                        np.zeros(a.shape[1])).reshape(len(a), len(b))


class _Checker:
    """The segment checks of one search, each segment once, counted."""

    def __init__(self, obj: Objective, world: CollisionWorld, law: TimeLaw, timing: Timing,
                 stop: Callable[[], object] | None) -> None:
        self.obj, self.world, self.law, self.timing, self.stop = obj, world, law, timing, stop
        self.count = 0
        self._seen: dict[bytes, Clearance] = {}
        # every segment keeps the start's limits: a pair within the padding at the start
        # comes no closer than there anywhere along the motion
        self._limits = StartLimits.at(world, obj.start)

    def spent(self, budget: int) -> bool:
        """Return whether the checks have reached ``budget`` or the caller asks to stop."""
        return self.count >= budget or (self.stop is not None and self.stop() is not None)

    def known(self, a: np.ndarray, b: np.ndarray) -> bool:
        """Return whether the segment from a to b was checked and found free."""
        seen = self._seen.get(a.tobytes() + b.tobytes())
        return seen is not None and seen.free

    def segment(self, a: np.ndarray, b: np.ndarray) -> Clearance:
        """Return how the direct motion from a to b (planned joints) keeps clear."""
        key = a.tobytes() + b.tobytes()
        if key not in self._seen:
            self.count += 1
            full_a, full_b = self.obj.full(a)[0], self.obj.full(b)[0]
            self._seen[key] = check_motion(self.world, full_a, full_b, self.law, self.timing,
                                           True, self._limits)
        return self._seen[key]

    def through(self, via: np.ndarray, goal: np.ndarray) -> Detour | None:
        """Return the motion start -> via -> goal if both segments are free, else None."""
        start = self.obj.planned_start
        there = self.segment(start, via)
        if not there.free:
            return None
        on = self.segment(via, goal)
        if not on.free:
            return None
        return self._detour((start, via, goal), (there, on))

    def through_both(self, a: np.ndarray, b: np.ndarray, goal: np.ndarray) -> Detour:
        """Return the motion start -> a -> b -> goal, its segments checked free already."""
        points = (self.obj.planned_start, a, b, goal)
        return self._detour(points, tuple(self.segment(p, q) for p, q in zip(points, points[1:])))

    def _detour(self, points: tuple[np.ndarray, ...], segments: tuple[Clearance, ...]) -> Detour:
        """Return the motion through ``points`` (planned joints) whose segments keep clear so."""
        least = min(segments, key=lambda c: c.clearance)
        duration = sum(float(_durations(self.obj, p[None], q[None])[0, 0])
                       for p, q in zip(points, points[1:]))
        return Detour(points[-1], tuple(self.obj.full(v)[0] for v in points[1:-1]), least,
                      duration, self.count)


def _pulled(obj: Objective, check: _Checker, found: Detour) -> Detour:
    """Return ``found`` with its via point moved towards the direct motion where that helps."""
    via = found.vias[0][:obj.arm.planned]
    middle = 0.5 * (obj.planned_start + found.x)
    low, high, best = 0.0, 1.0, found
    for _ in range(BISECTIONS):
        if check.spent(check.count + 2):
            break
        share = 0.5 * (low + high)
        trial = check.through((1.0 - share) * via + share * middle, found.x)
        if trial is not None and trial.duration < best.duration:
            low, best = share, trial
        else:
            high = share
    return Detour(best.x, best.vias, best.clearance, best.duration, check.count)
