# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The continuous check of a direct motion against the arm's links and the scene.

``check_motion`` follows the swept motion under the plan's profile and timing on a
grid of instants fine enough that no point of any link moves by more than ``GRID_SWEEP`` from
one to the next. Every joint of a rest-to-rest motion turns one way only, so between instants
t_k and t the links of pair p come closer by at most b_p(t) - b_p(t_k), with
b_p(t) = sum_j |q_j(t) - q_j(0)| sweep[p, j] (``CollisionWorld.sweep``: the farthest point of
either link from joint j's axis). A pair is checked at t_k, then next at the last instant
before that bound reaches its clearance less the padding: so at every instant of the motion,
not only the checked ones, every pair keeps the padding. The clearance at a checked instant is
first bounded below by the spheres (``collision.spheres``), then by the convex hulls
(``collision.convex``); a pair they leave less than one grid step is decided exactly by coal,
with the padding plus that step as margin.

A pair already within the padding at the start (or in contact) is held to its start clearance
less ``START_TOLERANCE`` instead: the motion may leave, not come closer (by more than the
check's resolution).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trajplan_ros.collision.arm_geometry import LinkFrames, poses_at
from trajplan_ros.collision.convex import ConvexArrays, pair_convex_bounds
from trajplan_ros.collision.distances import CollisionWorld
from trajplan_ros.collision.spheres import pair_lower_bounds, SphereBounds
from trajplan_ros.kinematics.jit import kernel
from trajplan_ros.motion.motion_profile import Timing
from trajplan_ros.motion.time_law import motion_times, TimeLaw
from trajplan_ros.motion.trajectory import motion_states

__all__ = ['Clearance', 'GRID_SWEEP', 'check_motion', 'colliding_pairs', 'START_TOLERANCE',
           'StartLimits']

#: Most any link point moves between two instants of the grid (m).
GRID_SWEEP = 1e-3
#: Most instants of the grid.
MAX_GRID = 20_000
#: How much closer (m) a pair within the padding at the start may come: the check's resolution.
START_TOLERANCE = 2 * GRID_SWEEP
#: Most piece pairs noted at one instant for coal to measure (more: coal measures the pairs).
FOUND_ROWS = 4096


@dataclass(frozen=True)
class Clearance:
    """How a motion keeps clear: free or not, its least clearance (m), where and when (s)."""

    free: bool
    clearance: float
    pair: str
    time: float
    start_within: str = ''       # the pair within the padding at the start, if any

    def describe(self) -> str:
        """Return the clearance in words."""
        if not self.pair:
            return 'nothing to collide with'
        verb = 'least clearance' if self.free else 'collides'
        return f'{verb} {self.clearance:.4g} m: {self.pair} at {self.time:.3f} s'


def _grid(world: CollisionWorld, start: np.ndarray, goal: np.ndarray, law: TimeLaw,
          timing: Timing) -> tuple[np.ndarray, np.ndarray]:
    """Return the instants (M,) of the check and the motion's joint angles there (M, n)."""
    duration = float(motion_times(law, goal[None], start)[0])
    swept = float(np.max(world.sweep @ np.abs(goal - start), initial=0.0))
    count = int(min(MAX_GRID, max(2, np.ceil(swept / GRID_SWEEP) + 1)))
    t = np.linspace(0.0, duration, count)
    return t, motion_states(start, goal, law, timing, t)[0]


@dataclass(frozen=True)
class StartLimits:
    """Each pair's limit (m) on motions from one start, and the pairs within the padding there."""

    limit: np.ndarray
    within: str

    @classmethod
    def at(cls, world: CollisionWorld, start: np.ndarray) -> StartLimits:
        """Return the limits at ``start``: the padding, or a closer start's clearance less 2 mm."""
        limit = np.full(len(world.pairs), world.padding)
        at_start = _clearances(world, world.arm.geometry.link_poses(start[None])[0],
                               np.arange(len(world.pairs)))
        close = np.flatnonzero(at_start <= world.padding)
        limit[close] = at_start[close] - START_TOLERANCE
        return cls(limit, ', '.join(world.pair_name(p) for p in close))


def check_motion(world: CollisionWorld, start: np.ndarray, goal: np.ndarray, law: TimeLaw,
                 timing: Timing, exact_clearance: bool = False,
                 limits: StartLimits | None = None) -> Clearance:
    """
    Return whether the motion from ``start`` to ``goal`` keeps every pair clear (see above).

    ``exact_clearance``: the least clearance is computed on coal's hulls for every pair the
    spheres bring near (a bound never above the true one, and exact where it is within the
    limit); otherwise a pair decided on the spheres reports their bound. ``limits``: the
    pairs' limits from ``start`` (``StartLimits.at``), when known already.
    """
    if not len(world.pairs):
        return Clearance(True, float('inf'), '', 0.0)
    limits = StartLimits.at(world, start) if limits is None else limits
    limit, within = limits.limit, limits.within
    t, q = _grid(world, start, goal, law, timing)
    due = np.zeros(len(world.pairs), dtype=np.int64)
    least = np.array([np.inf, -1.0, 0.0])                  # clearance, pair, instant
    _clear_by_tables(world, q, limit, due, least)
    end = world.arm.geometry.link_poses(goal[None])[0]
    blocked = _blocked_at(world, end, np.where(due < len(t), limit, -np.inf))
    if blocked is not None:                          # most colliding candidates end in it
        return Clearance(False, world.padding, world.pair_name(blocked), float(t[-1]), within)
    moved = np.ascontiguousarray(np.abs(q - start) @ world.sweep.T)     # b_p(t), (M, P)
    margin = 0.0 if exact_clearance else -np.inf
    frames, spheres = world.arm.geometry.frames, world.sphere_bounds
    convexes = world.convexes.arrays
    k = int(due.min())
    while k < len(t):
        k, which, value, step, near, poses, notes, complete = check_pass(
            frames, spheres, convexes, world.pairs, q, moved, limit, due, k, margin, least)
        if k == len(t):
            break
        needed = limit[which] + step
        for n in np.flatnonzero(near):
            value[n] = (world.decide(poses, which[n], notes[notes[:, 0] == n], needed[n])
                        if complete else world.bounded(poses, which[n:n + 1], needed[n:n + 1],
                                                       exact_clearance, True)[0][0])
        bad = np.flatnonzero(value <= needed)
        if bad.size:
            p = which[bad[0]]
            return Clearance(False, float(value[bad[0]]), world.pair_name(p), float(t[k]), within)
        write_next_checks(moved, which, k, value, limit, due, least)
        k = int(due.min())
    return Clearance(True, float(least[0]), world.pair_name(int(least[1])),
                     float(t[int(least[2])]), within)


def _clear_by_tables(world: CollisionWorld, q: np.ndarray, limit: np.ndarray, due: np.ndarray,
                     least: np.ndarray) -> None:
    """
    Leave out of the check the pairs whose table (``PairTable``) keeps them over their limit.

    Their table bounds them over the whole turn of their joint from q[0] to q[-1], not only
    at the grid's instants; such a bound also stands for their least clearance.
    """
    for table in world.arm.tables:
        turn = q[:, table.joint]
        bound = table.least(turn[0], turn[-1])
        if bound > limit[table.pair]:
            due[table.pair] = len(q)
            if bound < least[0]:
                least[:] = bound, table.pair, np.argmin(np.abs(turn - table.lowest(turn[0],
                                                                                   turn[-1])))


@kernel
def check_pass(frames: LinkFrames, spheres: SphereBounds, convexes: ConvexArrays,
               pairs: np.ndarray, q: np.ndarray, moved: np.ndarray, limit: np.ndarray,
               due: np.ndarray, k: int, margin: float, least: np.ndarray) -> tuple:
    """
    Go on with the check from instant k while the spheres and hulls decide every pair due.

    At each instant the pairs due (``due`` <= k) get their sphere bounds at the link poses
    (``poses_at``, ``pair_lower_bounds``); a pair whose spheres come within a grid step of its
    limit (or, with a finite ``margin``, below the least clearance so far or within ``margin``
    of this instant's least) gets the larger bound of
    its convex sets (``convex.body_bound``: the link's hull, then its shapes'; for a possible
    least, the shapes' always). While none comes within a grid step of its limit they are
    scheduled (``write_next_checks``) and the check moves on to the next instant due. Returns
    that instant (len(q): every instant is checked), the pairs due there, their bounds, how far
    each may come closer by the next instant, which of them coal must decide (the triangles),
    and the link poses.
    """
    last = len(q) - 1
    found, count = np.empty((FOUND_ROWS, 4)), np.zeros(1, np.int64)
    while k <= last:
        which = np.flatnonzero(due <= k)
        poses = poses_at(frames, q[k])
        value = pair_lower_bounds(poses, spheres, pairs[which])
        step = moved[min(k + 1, last)][which] - moved[k][which]
        need = limit[which] + step
        least_may = value < least[0] + margin                    # may be the least
        asked = np.flatnonzero((value <= need) | least_may)
        count[0] = 0
        if len(asked):
            value[asked] = np.maximum(value[asked], pair_convex_bounds(
                convexes, poses, pairs[which[asked]], need[asked], least_may[asked], found,
                count))
        near = value <= need
        if near.any():
            notes = found[:min(count[0], len(found))].copy()
            for r in range(len(notes)):
                notes[r, 0] = asked[int(notes[r, 0])]
            return k, which, value, step, near, poses, notes, count[0] <= len(found)
        write_next_checks(moved, which, k, value, limit, due, least)
        k = np.min(due)
    nothing = np.empty(0)
    return (len(q), np.empty(0, np.int64), nothing, nothing, np.empty(0, np.bool_),
            np.empty((0, 4, 4)), np.empty((0, 4)), True)


@kernel
def write_next_checks(moved: np.ndarray, which: np.ndarray, k: int, value: np.ndarray,
                      limit: np.ndarray, due: np.ndarray, least: np.ndarray) -> None:
    """
    Write into ``due`` when pairs ``which``, clear by ``value`` at instant k, are next checked.

    ``next_checks`` gives the instants; ``least`` (clearance, pair, instant) keeps the least.
    """
    due[which] = next_checks(moved, which, k, value - limit[which])
    n = np.argmin(value)
    if value[n] < least[0]:
        least[0], least[1], least[2] = value[n], which[n], k


@kernel
def next_checks(moved: np.ndarray, which: np.ndarray, k: int, slack: np.ndarray) -> np.ndarray:
    """
    Return the next instant to check each pair ``which`` at (len(moved): never again).

    It is the last instant before the pair's bound b_p(t) - b_p(t_k) (``moved``, (M, P))
    reaches its ``slack`` (clearance less its limit), and at least k + 1.
    """
    out = np.empty(len(which), dtype=np.int64)
    last = len(moved) - 1
    for n in range(len(which)):
        p = which[n]
        reach = moved[k, p] + slack[n]
        if moved[last, p] < reach:
            out[n] = len(moved)
            continue
        low, high = k, last                  # moved[low] < reach <= moved[high]
        while high - low > 1:
            middle = (low + high) // 2
            if moved[middle, p] < reach:
                low = middle
            else:
                high = middle
        out[n] = max(low, k + 1)
    return out


def _blocked_at(world: CollisionWorld, poses: np.ndarray, limit: np.ndarray) -> int | None:
    """
    Return a pair within its limit at link poses, or None.

    The spheres, then the convex sets (``pair_convex_bounds``) pass most pairs; coal measures
    the pieces they leave open (``CollisionWorld.decide``), the deepest first.
    """
    near = np.flatnonzero(world.lower_bounds(poses, np.arange(len(world.pairs))) <= limit)
    found, count = np.empty((FOUND_ROWS, 4)), np.zeros(1, dtype=np.int64)
    bounds = pair_convex_bounds(world.convexes.arrays, poses, world.pairs[near], limit[near],
                                np.zeros(len(near), dtype=np.bool_), found, count)
    notes = found[:min(count[0], FOUND_ROWS)]
    for n in np.flatnonzero(bounds <= limit[near])[np.argsort((bounds - limit[near])[
            bounds <= limit[near]], kind='stable')]:
        p = int(near[n])
        if count[0] <= FOUND_ROWS:
            value = world.decide(poses, p, notes[notes[:, 0] == n], float(limit[p]))
        else:
            value = world.bounded(poses, near[n:n + 1], limit[p:p + 1], decide=True)[0][0]
        if value <= limit[p]:
            return p
    return None


def colliding_pairs(world: CollisionWorld, q: np.ndarray) -> str:
    """Return the pairs that touch or overlap at joint angles q, named ('' if none)."""
    at = _clearances(world, world.arm.geometry.link_poses(q[None])[0],
                     np.arange(len(world.pairs)))
    return ', '.join(world.pair_name(p) for p in np.flatnonzero(at <= 0.0))


def _clearances(world: CollisionWorld, poses: np.ndarray, which: np.ndarray) -> np.ndarray:
    """Return lower bounds of the pairs' distances, exact where they fall within the padding."""
    out = world.lower_bounds(poses, which)
    near = np.flatnonzero(out <= world.padding)
    if near.size:
        out[near] = world.bounded(poses, which[near], np.full(near.size, world.padding))[0]
    return out
