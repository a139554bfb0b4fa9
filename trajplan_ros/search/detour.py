# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Motions through via points: where no direct motion to the goal is free, the fastest found.

Not part of the paper. The motion is start -> v -> joint goal, each segment a direct motion
under the plan's profile and timing from rest to rest, so each keeps the padding along its
whole length by the same continuous check as a direct motion (``free_motion.check_motion``).
Its duration is the sum of the segments' (eq. 10 for each). The joint goals are the goal's
solutions whose own pose is clear (``_clear_goals``: the free-goal search's, more drawn where
too few are), fastest first; v among joint vectors drawn inside the limits (the held joints at
their start). Pairs (v, joint goal) are checked in the order of their duration, each segment
once, while that beats the best motion found. A free one is then shortened: each via point
clipped towards the least-time box (``_tightened``), then corners cut (``_shortcut``), which
may leave up to ``MOST_VIAS`` via points. Where no pair is free within ``CHECKS`` segments, two
via points: a from the via points the start reaches freely, b from those that reach a joint
goal freely, joined by a third free segment (``_two_vias``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from trajplan_ros.collision.distances import CollisionWorld
from trajplan_ros.collision.free_motion import check_motion, Clearance, StartLimits
from trajplan_ros.motion.motion_profile import Timing
from trajplan_ros.motion.time_law import joint_reach, motion_times, TimeLaw
from trajplan_ros.search.free_goal import reached_goals
from trajplan_ros.search.objective import Objective

__all__ = ['Detour', 'detour']

#: Via points drawn inside the limits.
VIAS = 96
#: Joint goals tried, fastest first.
GOALS = 6
#: Most segments checked before the search gives up.
CHECKS = 240
#: Bisection steps towards the least-time motion, per via point.
BISECTIONS = 6
#: Random moves of each via point after the bisection.
TRIES = 24
#: Tries to cut a corner of the motion, and the most via points that leaves.
SHORTCUTS = 80
MOST_VIAS = 4
#: The least share of the duration a cut corner must save: a rest more is worth no less.
CUT_GAIN = 0.02
#: Most rounds of random joint goals drawn where too few known ones are clear.
ROUNDS = 3


@dataclass(frozen=True)
class Detour:
    """A motion through via points: its joint goal, the via points, how it keeps clear."""

    x: np.ndarray                        # the joint goal, planned joints
    vias: tuple[np.ndarray, ...]         # every joint's angles at each via point
    clearance: Clearance                 # the least clearance over the segments
    duration: float                      # s, the segments' durations summed


def detour(obj: Objective, world: CollisionWorld, law: TimeLaw, timing: Timing,
           goals: np.ndarray, rng: np.random.Generator, tolerance: float,
           stop: Callable[[], object] | None = None, more_goals: bool = True) -> Detour | None:
    """
    Return the fastest motion found from the start through via points to a joint goal, or None.

    ``goals`` (K, planned): the goal's reached joint solutions, fastest first; ``law``: the
    whole arm's time law; ``tolerance``: the largest error (m) of a reached goal; ``stop``:
    asked before every check, anything but None ends the search with what it has;
    ``more_goals``: False keeps to ``goals`` (a joint goal), never drawing other solutions.
    See the module docstring.
    """
    check = _Checker(obj, world, law, timing, stop)
    goals, best = _clear_goals(obj, check, goals, rng, tolerance if more_goals else None)
    if not len(goals):                       # every joint goal found is itself in collision
        return None
    start = obj.planned_start
    vias = _vias(obj, goals, rng)
    first = _durations(obj, vias, start[None, :])[:, 0]                    # (V,)
    second = _durations(obj, vias, goals)                                   # (V, G)
    total = (first[:, None] + second).ravel()
    for flat in np.argsort(total, kind='stable'):
        if check.spent(CHECKS) or (best is not None and total[flat] >= best.duration):
            return best
        v, g = divmod(int(flat), len(goals))
        found = check.through_points((start, vias[v], goals[g]))
        if found is not None:         # the fastest pair free; the search goes on for one
            found = _shortcut(obj, check, _tightened(obj, check, found, rng), rng)
            best = found if best is None or found.duration < best.duration else best
    if best is not None:
        return best
    found = _two_vias(obj, check, vias, goals, first, second)
    return None if found is None else _shortcut(obj, check, _tightened(obj, check, found, rng),
                                                rng)


def _clear_goals(obj: Objective, check: _Checker, goals: np.ndarray, rng: np.random.Generator,
                 tolerance: float | None) -> tuple[np.ndarray, Detour | None]:
    """
    Return up to ``GOALS`` joint goals whose own pose keeps the padding, fastest first.

    The known ones first (their direct motions collide); where fewer are clear, up to
    ``ROUNDS`` rounds of the free-goal search's candidates (``reached_goals``, within
    ``tolerance``; None: none drawn): near an obstacle few of the goal's solutions are. A goal
    drawn here may have a free direct motion: the fastest found is returned too (else None).
    """
    clear = [g for g in goals if check.pose(g)][:GOALS]
    known, direct = len(clear), None
    for _ in range(ROUNDS if tolerance is not None else 0):
        if len(clear) >= GOALS or check.spent(check.count + 1):
            break
        clear += [g for g in reached_goals(obj, rng, tolerance) if check.pose(g)]
    for goal in sorted(clear[known:], key=lambda g: float(obj.motion_time(g[None])[0])):
        if check.spent(CHECKS):
            break
        direct = check.through_points((obj.planned_start, goal))
        if direct is not None:
            break
    if not clear:
        return np.empty((0, obj.arm.planned)), direct
    clear = np.array(clear)
    return clear[np.argsort(obj.motion_time(clear), kind='stable')][:GOALS], direct


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
                return check.through_points((obj.planned_start, vias[reached[a]],
                                             vias[onward[b]], goals[g]))
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

    def segment(self, a: np.ndarray, b: np.ndarray, counted: bool = True) -> Clearance:
        """Return how the direct motion from a to b (planned joints) keeps clear."""
        key = a.tobytes() + b.tobytes()
        if key not in self._seen:
            self.count += counted
            full_a, full_b = self.obj.full(a)[0], self.obj.full(b)[0]
            self._seen[key] = check_motion(self.world, full_a, full_b, self.law, self.timing,
                                           True, self._limits)
        return self._seen[key]

    def through_points(self, points: tuple[np.ndarray, ...]) -> Detour | None:
        """Return the motion through ``points`` (start first) if every segment is free."""
        segments = []
        for p, q in zip(points, points[1:]):
            segments.append(self.segment(p, q))
            if not segments[-1].free:
                return None
        return self._detour(points, tuple(segments))

    def pose(self, x: np.ndarray) -> bool:
        """Return whether the arm at rest at x (planned joints) keeps the padding."""
        return self.segment(x, x, counted=False).free     # one instant: not a motion's cost

    def _detour(self, points: tuple[np.ndarray, ...], segments: tuple[Clearance, ...]) -> Detour:
        """Return the motion through ``points`` (planned joints) whose segments keep clear so."""
        least = min(segments, key=lambda c: c.clearance)
        return Detour(points[-1], tuple(self.obj.full(v)[0] for v in points[1:-1]), least,
                      _duration(self.obj, points))


def _tightened(obj: Objective, check: _Checker, found: Detour, rng: np.random.Generator
               ) -> Detour:
    """
    Return ``found`` with each via point moved towards the least-time motion where it helps.

    Via point v between points p and n, the motion through it taking t1 + t2 s: for a total
    D between the direct motion's T(p, n) and t1 + t2, v is clipped into the box of the points
    each joint reaches from p in D t1 / (t1 + t2) and from n in D t2 / (t1 + t2) s
    (``joint_reach``): at D = t1 + t2 that is v itself, at D = T(p, n) a via point that costs
    nothing over the direct motion. D is bisected, each step kept where both segments stay free
    and the motion gets shorter. Then ``TRIES`` times, v moved by normal noise on the scale of
    the detour's extra turn is clipped into the box of a D drawn below t1 + t2: a shorter motion
    around the obstacle's other side or edge, kept where it is free.
    """
    points = [obj.planned_start, *(v[:obj.arm.planned] for v in found.vias), found.x]
    best = found
    for k in range(1, len(points) - 1):
        anchor, low, high = points[k], 0.0, 1.0
        for attempt in range(BISECTIONS + TRIES):
            if check.spent(check.count + 2):
                break
            if attempt < BISECTIONS:
                share = 0.5 * (low + high)
                via = _shortened(obj, anchor, anchor, points[k - 1], points[k + 1], share)
            else:
                extra = best.duration - _time(obj, points[k - 1], points[k + 1])
                moved = points[k] + (extra * obj.law.velocity
                                     * rng.standard_normal(obj.arm.planned))
                via = _shortened(obj, points[k], np.clip(moved, obj.lower, obj.upper),
                                 points[k - 1], points[k + 1], rng.uniform())
            trial = None if via is None else check.through_points(
                (*points[:k], via, *points[k + 1:]))
            better = trial is not None and trial.duration < best.duration
            if better:
                best, points[k] = trial, via
            if attempt < BISECTIONS:
                high, low = (share, low) if better else (high, share)
    return best


def _shortcut(obj: Objective, check: _Checker, found: Detour, rng: np.random.Generator
              ) -> Detour:
    """
    Return ``found`` with corners cut, as a sampling planner's path simplification does.

    ``SHORTCUTS`` times: a point a on one segment and b on a later one (at random fractions
    of the way between their ends) replace the points between them, where the motion gets
    shorter by ``CUT_GAIN`` of its duration (durations first, then the checks), has at most
    ``MOST_VIAS`` via points and the segments to a, from a to b and from b are free.
    """
    points = [obj.planned_start, *(v[:obj.arm.planned] for v in found.vias), found.x]
    best = found
    for _ in range(SHORTCUTS):
        if check.spent(check.count + 3):
            break
        i, j = sorted(rng.choice(len(points) - 1, 2, replace=False))
        u, w = rng.uniform(size=2)
        a = points[i] + u * (points[i + 1] - points[i])
        b = points[j] + w * (points[j + 1] - points[j])
        trial = (*points[:i + 1], a, b, *points[j + 1:])
        if (len(trial) - 2 > MOST_VIAS
                or _duration(obj, trial) >= (1.0 - CUT_GAIN) * best.duration):
            continue
        cut = check.through_points(trial)
        if cut is not None:
            best, points = cut, list(trial)
    return best


def _duration(obj: Objective, points: tuple[np.ndarray, ...]) -> float:
    """Return the duration of the motion through ``points``, at rest at each."""
    return sum(_time(obj, p, q) for p, q in zip(points, points[1:]))


def _time(obj: Objective, a: np.ndarray, b: np.ndarray) -> float:
    """Return the duration of the direct motion from a to b (planned joints)."""
    return float(_durations(obj, a[None], b[None])[0, 0])


def _shortened(obj: Objective, via: np.ndarray, moved: np.ndarray, before: np.ndarray,
               after: np.ndarray, share: float) -> np.ndarray | None:
    """
    Return ``moved`` clipped into the box of ``via``'s split at ``share`` of its extra time.

    The total is T(before, after) plus ``share`` of the time the motion through ``via`` takes
    beyond it, split between the two segments as through ``via``; None where the box is empty.
    """
    t1, t2, direct = _time(obj, before, via), _time(obj, via, after), _time(obj, before, after)
    total = direct + share * (t1 + t2 - direct)
    return _clipped(obj, moved, before, after, total * t1 / (t1 + t2), total * t2 / (t1 + t2))


def _clipped(obj: Objective, via: np.ndarray, before: np.ndarray, after: np.ndarray,
             t1: float, t2: float) -> np.ndarray | None:
    """Return via clipped into the points reached from before in t1 and after in t2 s."""
    law = obj.law
    reach_1 = np.array([joint_reach(law, j, t1) for j in range(len(via))])
    reach_2 = np.array([joint_reach(law, j, t2) for j in range(len(via))])
    low = np.maximum(before - reach_1, after - reach_2)
    high = np.minimum(before + reach_1, after + reach_2)
    if np.any(low > high):                     # under acceleration limits: too short a total
        return None
    return np.clip(via, low, high)
