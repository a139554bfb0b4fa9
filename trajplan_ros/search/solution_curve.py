# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The curve of solutions: follow it through every component, and seed the polish where it is fast.

Not part of the paper. Reaching a point with four planned joints (or the radial pose with six)
leaves one free direction: the solutions form curves, one per connected component (for the
paper's arm: per base branch, with both elbows on one closed curve when they meet). Joint limits
cut each curve into arcs, and the motion time along a curve can have several local minima, at
the end of an arc (a joint on its limit) or inside one. A local polish sees only its own
neighbourhood, and a swarm can miss a component whose basin is small. ``curve_seeds`` covers
them all:

1. probes: the answer and points drawn uniformly inside the limits, each moved onto the
   solution set by Newton steps (``project_onto_curves``); a component whose basin under these
   steps holds a fraction f of the joint space is missed with probability (1 - f)^probes;
2. every probe's curve is followed both ways, straight through the limits (``follow``), all in
   one vectorised walk;
3. the seeds are the samples where the motion time is no larger than at their neighbours, among
   the samples inside the limits, the points where the curve enters or leaves the limits
   (``limit_crossings``, so that an arc shorter than a step and an optimum on a limit are not
   missed) and the samples just outside a limit that are nearer to it than their neighbours,
   moved onto it (a curve that only touches a limit). The curve through the answer so far is
   also sampled ten times as finely near it: two minima can lie closer together than a step
   (near the edge of the workspace, where the curves are small and sharply bent).

Where the solutions are isolated (radial or approach goals on four or five planned joints, poses
on six) the curve is that of the position and of fewer conditions on the orientation (none, one
or two of them: ``curve_constraint``), and the seeds are where the tool comes nearest the goal
orientation instead. Every solution lies on those curves, and a curve's basin is larger than an
isolated solution's.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from trajplan_ros.kinematics.forward import Chain, chain_hessian, tool_rows
from trajplan_ros.kinematics.jit import inlined_kernel, kernel
from trajplan_ros.motion.time_law import joint_time, TimeLaw
from trajplan_ros.search.linearisation import (damped_pseudo_inverses, minimum_norm_steps,
                                               residuals_and_jacobians, solution_model)
from trajplan_ros.search.objective import errors_eq11, Objective, Problem, tool_angle

__all__ = ['curve_constraint', 'curve_keys', 'curve_seeds', 'distinct', 'distinct_by_spacing',
           'follow', 'limit_crossings', 'lowest_time', 'neighbours', 'newton_steps',
           'points_on_curves', 'project_onto_curves', 'seeds_on_curves', 'snap_to_limits', 'trace',
           'wrap_into']


def curve_constraint(obj: Objective) -> Objective | None:
    """
    Return the objective whose solutions form the curve to search, or None when there is none.

    That is obj itself where its constraints leave one free direction (free mode with four
    planned joints, radial with six, a pose with seven). Where the solutions are isolated
    points with the axis held (radial or approach with four or five planned joints, a pose
    with four to six), it holds the position and only as many orientation residuals as leave
    one free direction: the points lie on its curves, where the tool comes nearest the goal
    orientation.
    """
    planned = obj.arm.planned
    if obj.null_directions == 1:
        return obj
    if obj.null_directions == 0 and 0 <= planned - 4 < len(obj.across_basis):
        return obj.holding(planned - 4)
    return None


@kernel
def wrap_into(q: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> None:
    """Wrap angles q (N, m) to [-pi, pi), or to the box on joints whose box is a whole turn."""
    for i in range(q.shape[1]):
        turn = upper[i] - lower[i] >= 2.0 * np.pi - 1e-12
        centre = 0.5 * (lower[i] + upper[i]) if turn else 0.0
        for k in range(q.shape[0]):
            q[k, i] = centre + (q[k, i] - centre + np.pi) % (2.0 * np.pi) - np.pi


@kernel
def newton_steps(curve: Problem, x: np.ndarray, steps: int) -> np.ndarray:
    """Return x (K, m) after ``steps`` minimum-norm Newton steps, wrapped (see the caller)."""
    x = x.copy()
    unbounded = np.full(x.shape[0], np.inf)
    for _ in range(steps):
        c, jac = residuals_and_jacobians(tool_rows(curve.chain, x, True), curve.goal,
                                         curve.across)
        x += minimum_norm_steps(damped_pseudo_inverses(jac), c, unbounded)
        wrap_into(x, curve.lower, curve.upper)
    return x


@inlined_kernel
def _curve_model(curve: Problem, x: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return c, J^+, the null direction and half the solutions' curvature along it at x."""
    rows = tool_rows(curve.chain, x, True)
    c, jac = residuals_and_jacobians(rows, curve.goal, curve.across)
    pinv, null, quad = solution_model(jac, chain_hessian(rows, curve.chain.tail.shape[0]),
                                      curve.across, 1)
    return c, pinv, null[:, 0, :], quad[:, 0, 0, :]


@kernel
def trace(curve: Problem, x: np.ndarray, step: np.ndarray, steps: int) -> np.ndarray:
    """
    Return the curves of solutions through the rows of x (K, m), (K, 2 steps + 1, m) (``follow``).

    Each way from each row (the null direction, then its opposite): a step of ``step`` (K,)
    along the tangent and the curvature, then one Newton correction, the tangent's sign kept
    along the way; the samples wrapped (``wrap_into``), the walk itself not.
    """
    k, dim = x.shape
    ends = np.concatenate((x, x))
    unbounded = np.full(2 * k, np.inf)
    c, pinv, null, bend = _curve_model(curve, ends)
    direction = null.copy()
    direction[k:] *= -1.0
    length = np.concatenate((step, step))
    out = np.empty((k, 2 * steps + 1, dim))
    out[:, steps] = x
    for s in range(steps):
        for r in range(2 * k):
            for i in range(dim):
                ends[r, i] += (direction[r, i] + bend[r, i] * length[r]) * length[r]
        c, pinv, null, bend = _curve_model(curve, ends)
        ends += minimum_norm_steps(pinv, c, unbounded)
        for r in range(2 * k):
            turn = 0.0
            for i in range(dim):
                turn += null[r, i] * direction[r, i]
            for i in range(dim):
                direction[r, i] = null[r, i] * np.sign(turn)
        sample = ends.copy()
        wrap_into(sample, curve.lower, curve.upper)
        out[:, steps + 1 + s] = sample[:k]
        out[:, steps - 1 - s] = sample[k:]
    return out


def project_onto_curves(curve: Objective, x: np.ndarray, steps: int = 2) -> np.ndarray:
    """
    Return x (K, planned) moved towards the solutions of ``curve`` by minimum-norm Newton steps.

    The limits are ignored and angles wrapped (``wrap_into``). Rows that have not converged yet
    carry on converging in ``follow``, which corrects every step.
    """
    return newton_steps(curve.problem, np.ascontiguousarray(x, dtype=float), steps)


def follow(curve: Objective, x: np.ndarray, step: float | np.ndarray,
           steps: int) -> np.ndarray:
    """
    Sample the curves of solutions of ``curve`` through the rows of x (K, planned).

    Returns (K, 2 steps + 1, planned): each curve in order, with its row of x in the middle.
    ``steps`` predictor-corrector steps of ``step`` rad (one for all rows, or one per row) each
    way (a step along the tangent and the curvature of the solutions, then one Newton
    correction), straight through the joint limits (angles wrapped, ``wrap_into``).
    """
    x = np.ascontiguousarray(x, dtype=float)
    step = np.array(np.broadcast_to(step, (x.shape[0],)), dtype=float)
    return trace(curve.problem, x, step, steps)


@inlined_kernel
def limit_crossings(lower: np.ndarray, upper: np.ndarray, a: np.ndarray, b: np.ndarray
                    ) -> np.ndarray:
    """
    Return where the chords a -> b (K, m) enter and leave the joint limits, (3, K, m).

    The chord runs from a to a + wrap(b - a); NaN rows where it misses the limits. The third
    point is, for a chord that misses them by less than 0.1 rad, its point nearest to them
    (of nine along it), moved onto them: the curve bends away from its chords, and the part of
    an arc inside the limits can be shorter than a chord's miss (in a corner of the limits).
    """
    count, dim = a.shape
    out = np.full((3, count, dim), np.nan)
    d = np.empty(dim)
    t = np.empty(3)
    for k in range(count):
        if np.isnan(a[k]).any() or np.isnan(b[k]).any():
            continue                                  # no chord: NaN rows
        enter, leave = -np.inf, np.inf
        for i in range(dim):
            d[i] = (b[k, i] - a[k, i] + np.pi) % (2.0 * np.pi) - np.pi
            if d[i] != 0.0:
                t_lo, t_hi = (lower[i] - a[k, i]) / d[i], (upper[i] - a[k, i]) / d[i]
                enter, leave = max(enter, min(t_lo, t_hi)), min(leave, max(t_lo, t_hi))
            elif not lower[i] <= a[k, i] <= upper[i]:
                enter, leave = np.inf, -np.inf
        missed = max(enter, 0.0) > min(leave, 1.0)
        t[0], t[1], t[2] = max(enter, 0.0), min(leave, 1.0), np.nan
        if missed:
            t[0] = t[1] = np.nan
            gap, nearest = np.inf, 0
            for j in range(9):
                miss = -np.inf
                for i in range(dim):
                    at = a[k, i] + j / 8.0 * d[i]
                    miss = max(miss, lower[i] - at, at - upper[i])
                if miss < gap:
                    gap, nearest = miss, j
            if gap < 0.1:
                t[2] = nearest / 8.0
        for e in range(3):
            if not np.isnan(t[e]):
                for i in range(dim):
                    out[e, k, i] = min(max(a[k, i] + t[e] * d[i], lower[i]), upper[i])
    return out


class _Walk(NamedTuple):
    """The points along the curves through K probes (``_on_curves``)."""

    points: np.ndarray      # (K, L, planned), NaN where unusable
    samples: np.ndarray     # the samples of the walks, (K, S, planned)
    present: np.ndarray     # which points are on the curves at all (K, L): every sample, and
    #                         the crossing points that exist
    tool: np.ndarray        # the tool at each point, (K L, V, 3): its point and axes


def _on_curves(obj: Objective, curve: Objective, probes: np.ndarray, step: np.ndarray,
               steps: int) -> _Walk:
    """
    Return the points along the curves through the probes (``_Walk``).

    Each curve in order: a sample, where the chord to the next one enters the limits, where it
    leaves them, where it nearly meets them (``limit_crossings``), the next sample, and so on.
    A sample outside the limits that is nearer to them than both its neighbours is moved onto
    them. Points outside the limits or farther than 5e-2 of the reach from the solutions (the
    points moved onto the limits can be that far) are NaN.
    """
    along = follow(curve, project_onto_curves(curve, probes), step, steps)     # (K, S, planned)
    return _Walk(*points_on_curves(curve.problem, obj.chain, along))


@inlined_kernel
def snap_to_limits(along: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> None:
    """Move samples (K, S, m) onto the limits where they are just outside (``_on_curves``)."""
    k, count, dim = along.shape
    # on a limit, not outside it by a rounding error (a curve can lie on a limit: the base
    # joint's angle is the same all along it)
    outside = np.empty((k, count))
    for r in range(k):
        for s in range(count):
            outside[r, s] = -np.inf
            for i in range(dim):
                snap = min(max(along[r, s, i], lower[i]), upper[i])
                if abs(along[r, s, i] - snap) <= 1e-9:
                    along[r, s, i] = snap
                outside[r, s] = max(outside[r, s], lower[i] - along[r, s, i],
                                    along[r, s, i] - upper[i])
    # a sample outside the limits but nearer than both neighbours: where the curve may just
    # touch a limit from outside (a solution set of one point) or dip back in between samples
    for r in range(k):
        for s in range(count):
            before = outside[r, s - 1] if s > 0 else np.inf
            after = outside[r, s + 1] if s + 1 < count else np.inf
            if 0.0 < outside[r, s] <= min(before, after):
                for i in range(dim):
                    along[r, s, i] = min(max(along[r, s, i], lower[i]), upper[i])


@kernel
def points_on_curves(curve: Problem, chain: Chain, along: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Return ``_Walk``'s points, samples, present and tool for the samples ``along`` (K, S, m).

    See ``_on_curves``; ``along`` is changed in place (samples snapped onto the limits). The
    tool is the objective's, walked along its ``chain`` (with a pose's second axis, which the
    curve of fewer residuals need not carry).
    """
    lower, upper, reach = curve.lower, curve.upper, curve.reach
    k, count, dim = along.shape
    snap_to_limits(along, lower, upper)
    chords = (count - 1) * k
    ends = limit_crossings(lower, upper, along[:, :-1].copy().reshape((chords, dim)),
                           along[:, 1:].copy().reshape((chords, dim)))
    size = 4 * (count - 1) + 1
    points = np.empty((k, size, dim))
    present = np.ones((k, size), dtype=np.bool_)
    for r in range(k):
        for s in range(count - 1):
            points[r, 4 * s] = along[r, s]
            for e in range(3):
                points[r, 4 * s + 1 + e] = ends[e, r * (count - 1) + s]
                present[r, 4 * s + 1 + e] = not np.isnan(ends[e, r * (count - 1) + s, 0])
        points[r, size - 1] = along[r, count - 1]
    inside = np.empty(k * size, dtype=np.int64)        # the points inside the limits
    count_inside = 0
    for j in range(k * size):
        valid = True
        for i in range(dim):
            valid &= lower[i] <= points[j // size, j % size, i] <= upper[i]     # NaN: False
        if valid:
            inside[count_inside] = j
            count_inside += 1
        else:
            points[j // size, j % size] = np.nan
    flat = np.empty((count_inside, dim))
    for n in range(count_inside):
        flat[n] = points[inside[n] // size, inside[n] % size]
    rows = tool_rows(chain, flat, False)
    error = errors_eq11(rows, curve.goal, curve.ray, curve.across.shape[0], reach)
    tool = np.zeros((k * size, rows.shape[0], 3))
    for n in range(count_inside):
        j = inside[n]
        tool[j] = rows[:, n]
        if not error[n] <= 5e-2 * reach:
            points[j // size, j % size] = np.nan
    return points, along, present, tool


def curve_seeds(obj: Objective, probes: np.ndarray, best: np.ndarray | None, *,
                step: float = 0.7, steps: int = 12, fine: float = 0.05) -> np.ndarray:
    """
    Return seeds for ``polish`` along the curves through ``probes`` (see the module docstring).

    ``probes`` (K, planned) need not be solutions; none are returned where there is no curve.
    ``best`` is the answer so far (None when it does not reach the goal). Its curve is also
    sampled every ``fine`` rad near it, for minima closer to it than a ``step``. A seed is kept
    only if a faster solution than ``best`` may lie between its neighbours (``lowest_time``),
    and not within half a sample of ``best``. Of seeds within half a sample of each other only
    the best is kept (the same minimum, reached along the curves through different probes).
    On the fine samples of the curves of fewer axis conditions the
    neighbours of each seed are seeds too: near a fold of the arm (an elbow almost straight)
    two radial solutions can lie within one fine sample, and Newton's method from either side
    finds each.
    """
    curve = curve_constraint(obj)
    if curve is None:
        return np.empty((0, probes.shape[1]))
    spacing = np.full(len(probes), step)
    if best is not None:
        probes, spacing = np.concatenate((probes, best[None, :])), np.append(spacing, fine)
    walk = _on_curves(obj, curve, probes, spacing, steps)
    best = np.full(probes.shape[1], np.nan) if best is None else best
    return seeds_on_curves(*walk, spacing, obj.problem, curve is obj, best)


@inlined_kernel
def neighbours(present: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the index of the nearest present point before and after each point, (K, L) each.

    -1 where there is none before, L where there is none after.
    """
    k, count = present.shape
    before, after = np.empty((k, count), np.int64), np.empty((k, count), np.int64)
    for r in range(k):
        last = -1
        for j in range(count):
            before[r, j] = last
            if present[r, j]:
                last = j
        last = count
        for j in range(count - 1, -1, -1):
            after[r, j] = last
            if present[r, j]:
                last = j
    return before, after


@inlined_kernel
def lowest_time(samples: np.ndarray, spacing: np.ndarray, start: np.ndarray,
                law: TimeLaw) -> np.ndarray:
    """
    Return a lower bound of R near each point of ``_on_curves``, (K, L), from its samples.

    Between two neighbouring samples each joint is taken to move monotonically, give or take a
    tenth of the sample spacing (the curve bends between samples): its displacement is then no
    smaller than the lesser of its two ends less that tenth, or 0 where it changes sign; R is
    the largest t_i of those displacements (``law``). A sample is bounded over the stretches on
    either side of it, a point between two samples over theirs.
    """
    k, count, dim = samples.shape
    stretch = np.empty((k, count - 1))
    for r in range(k):
        for s in range(count - 1):
            largest = 0.0
            for i in range(dim):
                a, b = samples[r, s, i] - start[i], samples[r, s + 1, i] - start[i]
                if a * b > 0.0:
                    least = max(min(abs(a), abs(b)) - 0.1 * spacing[r], 0.0)
                    largest = max(largest, joint_time(law, i, least))
            stretch[r, s] = largest
    out = np.empty((k, 4 * (count - 1) + 1))
    for r in range(k):
        for s in range(count):
            before = stretch[r, s - 1] if s > 0 else np.inf
            after = stretch[r, s] if s < count - 1 else np.inf
            out[r, 4 * s] = min(before, after)
            if s < count - 1:
                out[r, 4 * s + 1: 4 * s + 4] = stretch[r, s]
    return out


@inlined_kernel
def distinct(points: np.ndarray, radius: float) -> np.ndarray:
    """
    Return the points (n, m), best first, ``radius`` (max-norm) or farther from all better ones.

    The first of each grid cell of size ``radius`` is kept first (cheap), then the pairs.
    """
    n, dim = points.shape
    cells = np.floor(points / radius)
    order = np.arange(n)
    for i in range(dim - 1, -1, -1):          # sorted by cell, each cell in its points' order
        order = order[np.argsort(cells[order, i], kind='mergesort')]
    first = np.zeros(n, dtype=np.bool_)
    for at in range(n):
        first[order[at]] = at == 0 or np.any(cells[order[at]] != cells[order[at - 1]])
    kept = points[first]
    keep = np.ones(kept.shape[0], dtype=np.bool_)
    for j in range(kept.shape[0]):
        for e in range(j):
            near = True
            for i in range(dim):
                near &= abs(kept[j, i] - kept[e, i]) < radius
            if near:
                keep[j] = False
                break
    return kept[keep]


@kernel
def curve_keys(points: np.ndarray, tool: np.ndarray, obj: Problem, by_time: bool) -> np.ndarray:
    """
    Return what the seeds minimise at the points (K, L, m) along the curves; inf at NaN ones.

    ``by_time``: the motion time R (eq. 10) of ``obj``, plus 1e-6 of the travel over omega (a
    tied stretch has one minimum); else the angle error of the ``tool`` (K L, V, 3) under
    ``obj``'s constraints (``tool_angle``).
    """
    k, count, dim = points.shape
    key = np.full((k, count), np.inf)
    # taken out of ``obj`` once: a field read in the loop takes a reference to its arrays each time
    start, law, omega, ray, held = obj.start, obj.law, obj.omega, obj.ray, obj.across.shape[0]
    for r in range(k):
        for j in range(count):
            if np.isnan(points[r, j, 0]):
                continue
            if by_time:
                largest, travel = 0.0, 0.0
                for i in range(dim):
                    moved = abs(points[r, j, i] - start[i])
                    largest = max(largest, joint_time(law, i, moved))
                    travel += moved
                key[r, j] = largest + 1e-6 * travel / omega
            else:
                key[r, j] = tool_angle(tool[r * count + j], ray, held)
    return key


@inlined_kernel
def distinct_by_spacing(points: np.ndarray, key: np.ndarray, minima: np.ndarray,
                        spacing: np.ndarray) -> np.ndarray:
    """
    Return the points (K, L, m) marked ``minima``, ``distinct`` within each sample spacing.

    The finest spacing first, then the coarser; best (least ``key``) first within each.
    """
    k, count, dim = points.shape
    out = np.empty((0, dim))
    size = -np.inf
    while True:                           # each spacing, the finest first
        coarser = np.inf
        for r in range(k):
            if size < spacing[r] < coarser:
                coarser = spacing[r]
        if coarser == np.inf:
            break
        size = coarser
        chosen = np.zeros((k, count), dtype=np.bool_)
        for r in range(k):
            chosen[r] = minima[r] & (spacing[r] == size)
        order = np.argsort(key.ravel()[chosen.ravel()], kind='mergesort')
        group = points.reshape((k * count, dim))[chosen.ravel()][order]
        out = np.concatenate((out, distinct(group, size / 2)))
    return out


@kernel
def seeds_on_curves(points: np.ndarray, samples: np.ndarray, present: np.ndarray,
                    tool: np.ndarray, spacing: np.ndarray, obj: Problem, by_time: bool,
                    best: np.ndarray) -> np.ndarray:
    """
    Return ``curve_seeds``'s seeds from the points along the curves (``_on_curves``).

    ``obj``: the objective's arrays (its start, time law, omega and targets); ``by_time``: the
    minima of the motion time (then of the travel), else of the angle error (``curve_keys``);
    ``best``: the answer so far (NaN: none).
    """
    k, count, dim = points.shape
    key = curve_keys(points, tool, obj, by_time)
    before, after = neighbours(present)
    minima = np.zeros((k, count), dtype=np.bool_)
    for r in range(k):
        for j in range(count):
            lo = key[r, before[r, j]] if before[r, j] >= 0 else np.inf
            hi = key[r, after[r, j]] if after[r, j] < count else np.inf
            minima[r, j] = np.isfinite(key[r, j]) and key[r, j] <= lo and key[r, j] <= hi
    if not np.isnan(best[0]):
        if not by_time:      # two radial solutions can lie within a fine sample (a fold)
            last = minima[k - 1].copy()
            for j in range(count):
                if last[j] and before[k - 1, j] >= 0:
                    minima[k - 1, before[k - 1, j]] = True
                if last[j] and after[k - 1, j] < count:
                    minima[k - 1, after[k - 1, j]] = True
            for j in range(count):
                minima[k - 1, j] &= np.isfinite(key[k - 1, j])
        best_time = 0.0
        for i in range(dim):
            best_time = max(best_time, joint_time(obj.law, i, abs(best[i] - obj.start[i])))
        bound = lowest_time(samples, spacing, obj.start, obj.law)
        for r in range(k):
            for j in range(count):
                far = False
                for i in range(dim):
                    far |= abs(points[r, j, i] - best[i]) >= spacing[r] / 2
                minima[r, j] &= bound[r, j] < best_time and far
    return distinct_by_spacing(points, key, minima, spacing)
