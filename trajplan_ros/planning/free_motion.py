# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Collision-free direct motions (issue 29): the continuous check and the search for the fastest.

The check (``check_motion``) follows the swept motion under the plan's profile and timing on a
grid of instants fine enough that no point of any link moves by more than ``GRID_SWEEP`` from
one to the next. Every joint of a rest-to-rest motion turns one way only, so between instants
t_k and t the links of pair p come closer by at most b_p(t) - b_p(t_k), with
b_p(t) = sum_j |q_j(t) - q_j(0)| sweep[p, j] (``CollisionWorld.sweep``: the farthest point of
either link from joint j's axis). A pair is checked at t_k, then next at the last instant
before that bound reaches its clearance less the padding: so at every instant of the motion,
not only the checked ones, every pair keeps the padding. The clearance at a checked instant is
first bounded below by the spheres (``collision.spheres``); a pair whose spheres leave less
than one grid step is decided exactly by coal, with the padding plus that step as margin.

A pair already within the padding at the start (or in contact) is held to its start clearance
less ``START_TOLERANCE`` instead: the motion may leave, not come closer (by more than the
check's resolution).

The search (``free_joint_goal``) is the direct method's own: the goal has a whole set of joint
solutions, and among them it takes the fastest whose motion is free. It checks the optimiser's
answer first; when that collides it projects random joint vectors onto the goal's solutions,
polishes copies of them to local minima of the motion time, checks them fastest first, and
moves the best free one towards faster colliding ones by bisection along the solutions.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trajplan_ros.collision.arm_geometry import poses_at
from trajplan_ros.collision.distances import CollisionWorld
from trajplan_ros.collision.spheres import pair_lower_bounds
from trajplan_ros.kinematics.jit import kernel
from trajplan_ros.planning.motion_profile import Timing
from trajplan_ros.planning.objective import Objective
from trajplan_ros.planning.polish import Linearisation, polish
from trajplan_ros.planning.time_law import motion_times, TimeLaw
from trajplan_ros.planning.trajectory import motion_states

__all__ = ['Clearance', 'GRID_SWEEP', 'check_motion', 'free_joint_goal', 'project',
           'SearchOutcome', 'START_TOLERANCE']

#: Most any link point moves between two instants of the grid (m).
GRID_SWEEP = 1e-3
#: Most instants of the grid.
MAX_GRID = 20_000
#: How much closer (m) a pair within the padding at the start may come: the check's resolution.
START_TOLERANCE = 2 * GRID_SWEEP
#: Random joint vectors the search projects onto the goal's solutions (a goal's free
#: solutions can be few: 48 missed the fastest free one on goals of the bench).
SAMPLES = 192
#: Newton steps of that projection.
PROJECTION_STEPS = 12
#: Bisection steps from the best free candidate towards a faster colliding one.
BISECTIONS = 6


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


def check_motion(world: CollisionWorld, start: np.ndarray, goal: np.ndarray, law: TimeLaw,
                 timing: Timing, exact_clearance: bool = False) -> Clearance:
    """
    Return whether the motion from ``start`` to ``goal`` keeps every pair clear (see above).

    ``exact_clearance``: the least clearance is computed exactly (coal) for every pair the
    spheres bring near; otherwise a pair decided on the spheres reports their bound.
    """
    if not len(world.pairs):
        return Clearance(True, float('inf'), '', 0.0)
    end = world.arm.geometry.link_poses(goal[None])[0]
    everything = np.arange(len(world.pairs))
    t, q = _grid(world, start, goal, law, timing)
    limit = np.full(len(world.pairs), world.padding)
    at_start = _clearances(world, world.arm.geometry.link_poses(q[:1])[0], everything)
    close = np.flatnonzero(at_start <= world.padding)
    limit[close] = at_start[close] - START_TOLERANCE
    within = ', '.join(world.describe(p) for p in close)
    blocked = _blocked_at(world, end, limit)
    if blocked is not None:                          # most colliding candidates end in it
        return Clearance(False, world.padding, world.describe(blocked), float(t[-1]), within)
    moved = np.ascontiguousarray(np.abs(q - start) @ world.sweep.T)     # b_p(t), (M, P)
    due = np.zeros(len(world.pairs), dtype=np.int64)
    least = np.array([np.inf, -1.0, 0.0])                  # clearance, pair, instant
    margin = world.padding if exact_clearance else -np.inf
    chain, spheres = world.arm.geometry.kernel_arrays, world.bound_arrays
    k = 0
    while k < len(t):
        k, which, value, step, near, poses = sphere_pass(chain, spheres, world.pairs, q, moved,
                                                         limit, due, k, margin, least)
        if k == len(t):
            break
        value[near] = world.exact(poses, which[near])
        bad = np.flatnonzero(value <= limit[which] + step)
        if bad.size:
            p = which[bad[0]]
            return Clearance(False, float(value[bad[0]]), world.describe(p), float(t[k]), within)
        settle(moved, which, k, value, limit, due, least)
        k = int(due.min())
    return Clearance(True, float(least[0]), world.describe(int(least[1])), float(t[int(least[2])]),
                     within)


@kernel
def sphere_pass(chain: tuple, spheres: tuple, pairs: np.ndarray, q: np.ndarray,
                moved: np.ndarray, limit: np.ndarray, due: np.ndarray, k: int, margin: float,
                least: np.ndarray) -> tuple:
    """
    Go on with the check from instant k while the spheres decide every pair due.

    At each instant the pairs due (``due`` <= k) get their sphere bounds at the link poses
    (``poses_at`` of ``chain``, ``pair_lower_bounds`` of ``spheres``). While none comes within a
    grid step of its limit (nor, with a finite ``margin``, below the least clearance so far or
    within ``margin`` of this instant's least) they are settled (``settle``) and the check moves
    on to the next instant due. Returns that instant (len(q): every instant is checked), the
    pairs due there, their bounds, how far each may come closer by the next instant, which of
    them coal must decide, and the link poses.
    """
    centres, radii, first, kinds, dims, inverse = spheres
    last = len(q) - 1
    while k <= last:
        which = np.flatnonzero(due <= k)
        poses = poses_at(*chain, q[k])
        value = pair_lower_bounds(poses, centres, radii, first, pairs[which], kinds, dims,
                                  inverse)
        step = moved[min(k + 1, last)][which] - moved[k][which]
        near = value - limit[which] <= step             # the spheres leave less than a step
        near |= value < min(least[0], np.min(value) + margin)      # may be the least clearance
        if near.any():
            return k, which, value, step, near, poses
        settle(moved, which, k, value, limit, due, least)
        k = np.min(due)
    nothing = np.empty(0)
    return (len(q), np.empty(0, np.int64), nothing, nothing, np.empty(0, np.bool_),
            np.empty((0, 4, 4)))


@kernel
def settle(moved: np.ndarray, which: np.ndarray, k: int, value: np.ndarray, limit: np.ndarray,
           due: np.ndarray, least: np.ndarray) -> None:
    """Schedule pairs ``which`` clear by ``value`` at instant k (``next_checks``); keep least."""
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
    """Return a pair within its limit at link poses (exact where the spheres come near)."""
    bounds = world.lower_bounds(poses, np.arange(len(world.pairs)))
    for p in np.flatnonzero(bounds <= limit):
        if world.within(poses, p, limit[p]):
            return int(p)
    return None


def _clearances(world: CollisionWorld, poses: np.ndarray, which: np.ndarray) -> np.ndarray:
    """Return the pairs' sphere bounds, made exact where they fall within the padding."""
    out = world.lower_bounds(poses, which)
    near = np.flatnonzero(out <= world.padding)
    if near.size:
        out[near] = world.exact(poses, which[near])
    return out


@dataclass(frozen=True)
class SearchOutcome:
    """The search's choice: planned joint angles x (None: no free motion found) and why."""

    x: np.ndarray | None
    clearance: Clearance          # the chosen motion's, or the blocked first candidate's
    checked: int                  # motions checked


def project(obj: Objective, x: np.ndarray, steps: int = PROJECTION_STEPS) -> np.ndarray:
    """Return joint vectors x (K, m) after Newton steps onto the goal's solutions."""
    for _ in range(steps):
        here = Linearisation(obj, x, 1.0, newton_only=True)
        x = np.clip(x + here.newton(here.c), obj.lower, obj.upper)
    return x


def _candidates(obj: Objective, rng: np.random.Generator, tolerance: float) -> np.ndarray:
    """Return reached joint goals, fastest first: random ones projected, and those polished."""
    projected = project(obj, rng.uniform(obj.lower, obj.upper, (SAMPLES, obj.arm.planned)))
    x = np.vstack((projected, polish(obj, projected)))
    x = x[obj.errors(*obj.tool(x)) <= tolerance]
    return x[np.argsort(obj.motion_time(x), kind='stable')]


def free_joint_goal(obj: Objective, world: CollisionWorld, law: TimeLaw, timing: Timing,
                    x0: np.ndarray, rng: np.random.Generator, tolerance: float
                    ) -> SearchOutcome:
    """
    Return the fastest joint goal found whose motion from the start is free (see the module).

    ``x0``: the optimiser's answer (planned joints), checked first; ``law``: the whole arm's
    time law; ``tolerance``: the largest error (m) of a reached goal.
    """
    def check(x: np.ndarray, exact: bool = False) -> Clearance:
        return check_motion(world, obj.start, obj.full(x)[0], law, timing, exact)

    first = check(x0, True)
    if first.free:
        return SearchOutcome(x0, first, 1)
    checked, colliding, best = 1, [x0], None
    for x in _candidates(obj, rng, tolerance):
        checked += 1
        if check(x).free:
            best = x
            break
        colliding.append(x)
    if best is None:
        return SearchOutcome(None, first, checked)
    for target in colliding[:3]:
        best, spent = _bisect(obj, check, best, target, tolerance)
        checked += spent
    return SearchOutcome(best, check(best, True), checked)


def _bisect(obj: Objective, check, free: np.ndarray, blocked: np.ndarray,
            tolerance: float) -> tuple[np.ndarray, int]:
    """Return the fastest free point found between ``free`` and ``blocked`` on the solutions."""
    low, high, best = 0.0, 1.0, free
    best_time = float(obj.motion_time(free[None])[0])
    for _ in range(BISECTIONS):
        middle = 0.5 * (low + high)
        x = project(obj, ((1.0 - middle) * free + middle * blocked)[None])
        reached = obj.errors(*obj.tool(x))[0] <= tolerance
        if reached and check(x[0]).free:
            low = middle
            if obj.motion_time(x)[0] < best_time:
                best, best_time = x[0], float(obj.motion_time(x)[0])
        else:
            high = middle
    return best, BISECTIONS
