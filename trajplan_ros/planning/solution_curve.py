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
   the samples inside the limits and the points where the curve enters or leaves the limits
   (``_limit_crossings``, so that an arc shorter than a step and an optimum on a limit are not
   missed).

Where radial solutions are isolated (four planned joints) the curve is that of the position
constraint alone, and the seeds are where the tool axis comes nearest the goal ray instead.
"""
from __future__ import annotations

import numpy as np

from trajplan_ros.planning.objective import Mode, Objective
from trajplan_ros.planning.polish import Linearisation

__all__ = ['curve_constraint', 'curve_seeds', 'follow', 'project']


def curve_constraint(obj: Objective) -> Objective | None:
    """
    Return the objective whose solutions form the curve to search, or None when there is none.

    That is obj itself where its constraints leave one free direction (free mode with four
    planned joints, radial with six), the position constraint alone in radial mode with four.
    """
    planned = obj.arm.planned
    if planned - (5 if obj.radial else 3) == 1:
        return obj
    if obj.radial and planned == 4:
        return Objective(obj.arm, obj.goal, obj.start, mode=Mode.FREE, omega=obj.omega)
    return None


def _wrap(q: np.ndarray) -> np.ndarray:
    return np.mod(q + np.pi, 2 * np.pi) - np.pi


def project(curve: Objective, x: np.ndarray, steps: int = 3) -> np.ndarray:
    """
    Return x (K, planned) moved towards the solutions of ``curve`` by minimum-norm Newton steps.

    The limits are ignored and angles wrapped to [-pi, pi). Rows that have not converged yet
    carry on converging in ``follow``, which corrects every step.
    """
    for _ in range(steps):
        here = Linearisation(curve, x, 1.0, curvature=False)
        x = _wrap(x + here.newton(here.c))
    return x


def follow(curve: Objective, x: np.ndarray, step: float, steps: int) -> np.ndarray:
    """
    Sample the curves of solutions of ``curve`` through the rows of x (K, planned).

    Returns (K, 2 steps + 1, planned): each curve in order, with its row of x in the middle.
    ``steps`` predictor-corrector steps of ``step`` rad each way (a tangent step, then one
    Newton correction), straight through the joint limits (angles wrapped to [-pi, pi)).
    """
    k = x.shape[0]
    ends = np.concatenate((x, x))
    here = Linearisation(curve, ends, 1.0, curvature=False)
    direction = here.null[:, 0, :] * np.repeat([1.0, -1.0], k)[:, None]    # both ways
    path = []
    for _ in range(steps):
        ends = ends + direction * step
        here = Linearisation(curve, ends, 1.0, curvature=False)
        ends = ends + here.newton(here.c)
        turn = np.sign(np.einsum('ki,ki->k', here.null[:, 0, :], direction))
        direction = here.null[:, 0, :] * turn[:, None]
        path.append(_wrap(ends))
    walk = np.stack(path, axis=1)                                    # (2K, steps, planned)
    return np.concatenate((walk[k:, ::-1], x[:, None, :], walk[:k]), axis=1)


def _limit_crossings(obj: Objective, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """
    Return where the chords a -> b enter and leave the joint limits, (2, K, planned).

    The chord runs from a to a + wrap(b - a); NaN rows where it misses the limits.
    """
    d = _wrap(b - a)
    with np.errstate(divide='ignore', invalid='ignore'):
        t_lo, t_hi = (obj.lower - a) / d, (obj.upper - a) / d
    moving = d != 0.0
    inside = (a >= obj.lower) & (a <= obj.upper)
    enter = np.where(moving, np.fmin(t_lo, t_hi), np.where(inside, -np.inf, np.inf)).max(axis=1)
    leave = np.where(moving, np.fmax(t_lo, t_hi), np.where(inside, np.inf, -np.inf)).min(axis=1)
    enter, leave = np.maximum(enter, 0.0), np.minimum(leave, 1.0)
    t = np.where(enter <= leave, np.stack((enter, leave)), np.nan)[:, :, None]
    return np.clip(a + t * d, obj.lower, obj.upper)


def _distinct(points: np.ndarray, radius: float) -> np.ndarray:
    """Return the indices of the points kept in order, each ``radius`` (max-norm) from the rest."""
    apart = np.max(np.abs(points[:, None, :] - points[None, :, :]), axis=2) >= radius
    kept: list[int] = []
    for i in range(len(points)):
        if all(apart[i, j] for j in kept):
            kept.append(i)
    return np.array(kept, dtype=int)


def _on_curves(obj: Objective, curve: Objective, probes: np.ndarray, step: float,
               steps: int) -> np.ndarray:
    """
    Return points along the curves through the probes, (K, L, planned); NaN where unusable.

    Each curve in order: a sample, where the chord to the next one enters the limits, where it
    leaves them, the next sample, and so on. Points outside the limits or farther than 1e-2 of
    the reach from the solutions are NaN.
    """
    along = follow(curve, project(curve, probes), step, steps)              # (K, S, planned)
    k, _, dim = along.shape
    ends = _limit_crossings(obj, along[:, :-1].reshape(-1, dim), along[:, 1:].reshape(-1, dim))
    crossings = ends.reshape(2, k, -1, dim).transpose(1, 2, 0, 3)
    points = np.concatenate((along[:, :-1, None], crossings), axis=2).reshape(k, -1, dim)
    flat = np.concatenate((points, along[:, -1:]), axis=1).reshape(-1, dim)
    valid = np.all((flat >= obj.lower) & (flat <= obj.upper), axis=1)      # NaN rows: False
    p, u = curve.tool(np.where(valid[:, None], flat, 0.0))
    valid &= curve.errors(p, u) <= 1e-2 * obj.arm.reach
    return np.where(valid[:, None], flat, np.nan).reshape(k, -1, dim)


def curve_seeds(obj: Objective, probes: np.ndarray, best: np.ndarray | None, *,
                step: float = 0.5, steps: int = 12) -> np.ndarray:
    """
    Return seeds for ``polish`` along the curves through ``probes`` (see the module docstring).

    ``probes`` (K, planned) need not be solutions; none are returned where there is no curve.
    ``best`` is the answer so far (None when it does not reach the goal): a seed is kept only
    if a faster solution may lie within a sample of it (R changes by at most 1/omega per
    radian of joint travel), and not within half a step of ``best``. Of seeds within half a
    step of each other only the best is kept (the same minimum, reached along the curves
    through different probes).
    """
    curve = curve_constraint(obj)
    if curve is None:
        return np.empty((0, probes.shape[1]))
    points = _on_curves(obj, curve, probes, step, steps)
    flat = points.reshape(-1, probes.shape[1])
    usable = ~np.isnan(flat[:, 0])
    q = np.where(usable[:, None], flat, 0.0)
    time = np.where(usable, obj.motion_time(q), np.inf).reshape(points.shape[:2])
    key = (time if curve is obj else
           np.where(usable, obj.axis_angle(obj.tool(q)[1]), np.inf).reshape(time.shape))
    pad_key, pad_time = (np.pad(v, ((0, 0), (1, 1)), constant_values=np.inf)
                         for v in (key, time))
    minima = np.isfinite(key) & (key <= pad_key[:, :-2]) & (key <= pad_key[:, 2:])
    neighbour = np.minimum(pad_time[:, :-2], pad_time[:, 2:])
    # the least R within a sample spacing (1.25 step, for the corrector's moves) of a minimum
    lowest = (np.where(np.isfinite(neighbour), (time + neighbour) / 2, time)
              - 0.625 * step / obj.omega)
    if best is not None:
        minima &= lowest < obj.motion_time(best[None, :])[0]
        minima &= np.max(np.abs(points - best), axis=2) >= step / 2
    seeds, order = flat[minima.ravel()], np.argsort(key[minima], kind='stable')
    return seeds[order][_distinct(seeds[order], step / 2)]
