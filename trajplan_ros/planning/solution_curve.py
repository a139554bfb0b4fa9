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
   solution set by Newton steps (``project``); a component whose basin under these steps holds
   a fraction f of the joint space is missed with probability (1 - f)^probes;
2. every probe's curve is followed both ways, straight through the limits (``follow``), all in
   one vectorised walk;
3. the seeds are the samples where the motion time is no larger than at their neighbours, among
   the samples inside the limits, the points where the curve enters or leaves the limits
   (``_limit_crossings``, so that an arc shorter than a step and an optimum on a limit are not
   missed) and the samples just outside a limit that are nearer to it than their neighbours,
   moved onto it (a curve that only touches a limit). The curve through the answer so far is
   also sampled ten times as finely near it: two minima can lie closer together than a step
   (near the edge of the workspace, where the curves are small and sharply bent).

Where radial solutions are isolated (four or five planned joints) the curve is that of the
position and of fewer conditions on the tool axis (none, or one of its two components across the
goal ray: ``curve_constraint``), and the seeds are where the tool axis comes nearest the goal ray
instead. Every radial solution lies on those curves, and a curve's basin is larger than an
isolated solution's.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from trajplan_ros.planning.objective import Mode, Objective
from trajplan_ros.planning.polish import Linearisation

__all__ = ['curve_constraint', 'curve_seeds', 'follow', 'project']


def curve_constraint(obj: Objective) -> Objective | None:
    """
    Return the objective whose solutions form the curve to search, or None when there is none.

    That is obj itself where its constraints leave one free direction (free mode with four
    planned joints, radial with six). In radial mode with four or five planned joints, where
    the solutions are isolated points, it holds the position and only as many components of
    the tool axis across the goal ray as leave one free direction (none, or one): the points
    lie on its curves, where the axis comes nearest the goal ray.
    """
    planned = obj.arm.planned
    if planned - 3 - len(obj.across_basis) == 1:
        return obj
    if obj.radial and planned in (4, 5):
        return Objective(obj.arm, obj.goal, obj.start, mode=Mode.RADIAL, omega=obj.omega,
                         across=planned - 4)
    return None


def _wrap(q: np.ndarray) -> np.ndarray:
    return np.mod(q + np.pi, 2 * np.pi) - np.pi


def _wrap_into(curve: Objective, q: np.ndarray) -> np.ndarray:
    """Wrap angles to [-pi, pi), or to the search box on joints whose box is a whole turn."""
    turn = curve.upper - curve.lower >= 2.0 * np.pi - 1e-12
    centre = np.where(turn, 0.5 * (curve.lower + curve.upper), 0.0)
    return centre + _wrap(q - centre)


def project(curve: Objective, x: np.ndarray, steps: int = 2) -> np.ndarray:
    """
    Return x (K, planned) moved towards the solutions of ``curve`` by minimum-norm Newton steps.

    The limits are ignored and angles wrapped (``_wrap_into``). Rows that have not converged yet
    carry on converging in ``follow``, which corrects every step.
    """
    for _ in range(steps):
        here = Linearisation(curve, x, 1.0, newton_only=True)
        x = _wrap_into(curve, x + here.newton(here.c))
    return x


def follow(curve: Objective, x: np.ndarray, step: float | np.ndarray,
           steps: int) -> np.ndarray:
    """
    Sample the curves of solutions of ``curve`` through the rows of x (K, planned).

    Returns (K, 2 steps + 1, planned): each curve in order, with its row of x in the middle.
    ``steps`` predictor-corrector steps of ``step`` rad (one for all rows, or one per row) each
    way (a step along the tangent and the curvature of the solutions, then one Newton
    correction), straight through the joint limits (angles wrapped, ``_wrap_into``).
    """
    k = x.shape[0]
    ends = np.concatenate((x, x))
    here = Linearisation(curve, ends, 1.0)
    direction = here.null[:, 0, :] * np.repeat([1.0, -1.0], k)[:, None]    # both ways
    length = np.tile(np.broadcast_to(step, (k,)), 2)[:, None]
    path = []
    for _ in range(steps):
        ends = ends + (direction + here.quad[:, 0, 0, :] * length) * length
        here = Linearisation(curve, ends, 1.0)
        ends = ends + here.newton(here.c)
        turn = np.sign(np.einsum('ki,ki->k', here.null[:, 0, :], direction))
        direction = here.null[:, 0, :] * turn[:, None]
        path.append(_wrap_into(curve, ends))
    walk = np.stack(path, axis=1)                                    # (2K, steps, planned)
    return np.concatenate((walk[k:, ::-1], x[:, None, :], walk[:k]), axis=1)


def _limit_crossings(obj: Objective, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """
    Return where the chords a -> b enter and leave the joint limits, (3, K, planned).

    The chord runs from a to a + wrap(b - a); NaN rows where it misses the limits. The third
    point is, for a chord that misses them by less than 0.1 rad, its point nearest to them
    (of nine along it), moved onto them: the curve bends away from its chords, and the part of
    an arc inside the limits can be shorter than a chord's miss (in a corner of the limits).
    """
    d = _wrap(b - a)
    with np.errstate(divide='ignore', invalid='ignore'):
        t_lo, t_hi = (obj.lower - a) / d, (obj.upper - a) / d
    moving = d != 0.0
    inside = (a >= obj.lower) & (a <= obj.upper)
    enter = np.where(moving, np.fmin(t_lo, t_hi), np.where(inside, -np.inf, np.inf)).max(axis=1)
    leave = np.where(moving, np.fmax(t_lo, t_hi), np.where(inside, np.inf, -np.inf)).min(axis=1)
    enter, leave = np.maximum(enter, 0.0), np.minimum(leave, 1.0)
    t = np.where(enter <= leave, np.stack((enter, leave)), np.nan)
    along = a[:, None, :] + np.linspace(0.0, 1.0, 9)[None, :, None] * d[:, None, :]
    miss = np.maximum(obj.lower - along, along - obj.upper).max(axis=2)          # (K, 9)
    nearest = np.argmin(miss, axis=1)
    gap = miss[np.arange(len(a)), nearest]
    t = np.concatenate((t, np.where((enter > leave) & (gap < 0.1), nearest / 8.0, np.nan)[None]))
    return np.clip(a + t[:, :, None] * d, obj.lower, obj.upper)


def _distinct(points: np.ndarray, radius: float) -> np.ndarray:
    """
    Return the points, best first, that are ``radius`` (max-norm) or farther from every better one.

    The first of each grid cell of size ``radius`` is kept first (cheap), then the pairs.
    """
    _, first = np.unique(np.floor(points / radius), axis=0, return_index=True)
    points = points[np.sort(first)]
    near = np.max(np.abs(points[:, None, :] - points[None, :, :]), axis=2) < radius
    return points[~np.any(np.tril(near, -1), axis=1)]


class _Walk(NamedTuple):
    """The points along the curves through K probes (``_on_curves``)."""

    points: np.ndarray      # (K, L, planned), NaN where unusable
    samples: np.ndarray     # the samples of the walks, (K, S, planned)
    present: np.ndarray     # which points are on the curves at all (K, L): every sample, and
    #                         the crossing points that exist
    axis: np.ndarray        # the tool axis at each point, (K L, 3)


def _on_curves(obj: Objective, curve: Objective, probes: np.ndarray, step: np.ndarray,
               steps: int) -> _Walk:
    """
    Return the points along the curves through the probes (``_Walk``).

    Each curve in order: a sample, where the chord to the next one enters the limits, where it
    leaves them, where it nearly meets them (``_limit_crossings``), the next sample, and so on.
    A sample outside the limits that is nearer to them than both its neighbours is moved onto
    them. Points outside the limits or farther than 5e-2 of the reach from the solutions (the
    points moved onto the limits can be that far) are NaN.
    """
    along = follow(curve, project(curve, probes), step, steps)              # (K, S, planned)
    k, _, dim = along.shape
    # on a limit, not outside it by a rounding error (a curve can lie on a limit: the base
    # joint's angle is the same all along it)
    snap = np.clip(along, obj.lower, obj.upper)
    along = np.where(np.abs(along - snap) <= 1e-9, snap, along)
    # a sample outside the limits but nearer than both neighbours: where the curve may just
    # touch a limit from outside (a solution set of one point) or dip back in between samples
    outside = np.maximum(obj.lower - along, along - obj.upper).max(axis=2)
    padded = np.pad(outside, ((0, 0), (1, 1)), constant_values=np.inf)
    touch = (outside > 0) & (outside <= padded[:, :-2]) & (outside <= padded[:, 2:])
    along = np.where(touch[:, :, None], snap, along)
    ends = _limit_crossings(obj, along[:, :-1].reshape(-1, dim), along[:, 1:].reshape(-1, dim))
    crossings = ends.reshape(3, k, -1, dim).transpose(1, 2, 0, 3)
    points = np.concatenate((along[:, :-1, None], crossings), axis=2).reshape(k, -1, dim)
    flat = np.concatenate((points, along[:, -1:]), axis=1).reshape(-1, dim)
    present = np.ones(flat.shape[0], dtype=bool).reshape(k, -1)
    present[:, :-1] = ~np.isnan(points[:, :, 0]) | (np.arange(points.shape[1]) % 4 == 0)
    valid = np.all((flat >= obj.lower) & (flat <= obj.upper), axis=1)      # NaN rows: False
    p, u = curve.tool(np.where(valid[:, None], flat, 0.0))
    valid &= curve.errors(p, u) <= 5e-2 * obj.arm.reach
    return _Walk(np.where(valid[:, None], flat, np.nan).reshape(k, -1, dim), along, present, u)


def _neighbours(present: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the index of the nearest present point before and after each point, (K, L) each.

    -1 where there is none before, L where there is none after.
    """
    count = present.shape[1]
    index = np.broadcast_to(np.arange(count), present.shape)
    before = np.maximum.accumulate(np.where(present, index, -1), axis=1)
    after = np.minimum.accumulate(np.where(present, index, count)[:, ::-1], axis=1)[:, ::-1]
    edge = np.full((len(present), 1), 1)
    return (np.concatenate((-edge, before[:, :-1]), axis=1),
            np.concatenate((after[:, 1:], count * edge), axis=1))


def _lowest_time(obj: Objective, samples: np.ndarray, spacing: np.ndarray) -> np.ndarray:
    """
    Return a lower bound of R near each point of ``_on_curves``, (K, L), from its samples.

    Between two neighbouring samples each joint is taken to move monotonically, give or take a
    tenth of the sample spacing (the curve bends between samples): its displacement is then no
    smaller than the lesser of its two ends, or 0 where it changes sign; R is the largest
    displacement over its joint's omega_i. A sample is bounded over the stretches on either side
    of it, a point between two samples over theirs.
    """
    moved = (samples - obj.start[: samples.shape[2]]) * obj.time_scale
    a, b = moved[:, :-1], moved[:, 1:]
    least = np.where(a * b <= 0.0, 0.0, np.minimum(np.abs(a), np.abs(b)))
    slack = 0.1 * spacing[:, None] * obj.time_scale.max()
    stretch = (np.max(least, axis=2) - slack) / obj.omega                          # (K, S - 1)
    padded = np.pad(stretch, ((0, 0), (1, 1)), constant_values=np.inf)
    at_samples = np.minimum(padded[:, :-1], padded[:, 1:])                       # (K, S)
    between = np.repeat(stretch, 3, axis=1).reshape(len(samples), -1, 3)
    points = np.concatenate((at_samples[:, :-1, None], between), axis=2).reshape(len(samples), -1)
    return np.concatenate((points, at_samples[:, -1:]), axis=1)


def curve_seeds(obj: Objective, probes: np.ndarray, best: np.ndarray | None, *,
                step: float = 0.7, steps: int = 12, fine: float = 0.05) -> np.ndarray:
    """
    Return seeds for ``polish`` along the curves through ``probes`` (see the module docstring).

    ``probes`` (K, planned) need not be solutions; none are returned where there is no curve.
    ``best`` is the answer so far (None when it does not reach the goal). Its curve is also
    sampled every ``fine`` rad near it, for minima closer to it than a ``step``. A seed is kept
    only if a faster solution than ``best`` may lie between its neighbours (``_lowest_time``),
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
    points, samples, present, axis = _on_curves(obj, curve, probes, spacing, steps)
    flat = points.reshape(-1, probes.shape[1])
    usable = ~np.isnan(flat[:, 0])
    q = np.where(usable[:, None], flat, 0.0)
    time = np.where(usable, obj.motion_time(q), np.inf).reshape(points.shape[:2])
    if curve is obj:             # least time, then least travel (a tied stretch has one minimum)
        travel = np.abs(q - obj.start[: q.shape[1]]).sum(axis=1).reshape(time.shape)
        key = time + 1e-6 * travel / obj.omega
    else:
        key = np.where(usable, obj.axis_angle(axis), np.inf).reshape(time.shape)
    before, after = _neighbours(present)
    padded = np.pad(key, ((0, 0), (0, 1)), constant_values=np.inf)      # index -1 and L: inf
    minima = (np.isfinite(key) & (key <= np.take_along_axis(padded, before, axis=1))
              & (key <= np.take_along_axis(padded, after, axis=1)))
    if best is not None:
        if curve is not obj:     # two radial solutions can lie within a fine sample (a fold)
            last = np.flatnonzero(minima[-1])
            minima[-1, before[-1, last][before[-1, last] >= 0]] = True
            minima[-1, after[-1, last][after[-1, last] < key.shape[1]]] = True
            minima[-1] &= np.isfinite(key[-1])
        minima &= _lowest_time(obj, samples, spacing) < obj.motion_time(best[None, :])[0]
        minima &= np.max(np.abs(points - best), axis=2) >= spacing[:, None] / 2
    groups = [(minima[spacing == size], key[spacing == size], points[spacing == size], size)
              for size in np.unique(spacing)]
    return np.concatenate([_distinct(p[m][np.argsort(k[m], kind='stable')], size / 2)
                           for m, k, p, size in groups])
