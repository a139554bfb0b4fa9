# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Local polish of candidate joint goals: exact reach, then least motion time along the solutions.

Not part of the paper. The swarm finds the basin; this finishes the job to machine precision.
It solves

    minimise max_i |x_i - start_i|   subject to   c(x) = 0 (reach, and the axis in radial mode),
                                                   lower <= x <= upper,

vectorised over K candidates, by sequential quadratic-model steps. Each step linearises c and
takes the minimum-norm Newton correction -J^+ c; then it moves along the null space of J (the
directions that keep the goal reached). Along a null direction n the solutions curve away from
the straight line; the exact second derivative of the kinematics gives that curvature
(x'' = -J^+ d2c/dz2), so each joint's displacement is modelled as a parabola in the step z.
The motion time, the largest of those |parabolas|, is minimised over z exactly by checking every
candidate point (vertices of the max, stationary points, zeros, bounds). That converges fast
both where two joints tie and where one joint's displacement is at a smooth minimum. Ties
(a stretch of solutions along which the slowest joint does not move, so R stays the same) go
to the least total joint travel sum |x_i - start_i|: the line search also checks where the
travel is least, and the merit omega R + 1e-6 travel + W |c| accepts a step that lowers the
travel at the same R. That makes plans repeatable. With more than one null direction (arms with
more than four planned joints) the directions are taken in turn, a coordinate descent that may
stop short of the optimum. A trust radius, a second-order correction and the merit make the
steps safe.

Being local, the polish cannot see a faster solution elsewhere on the curve of solutions
through its answer, or on another curve; ``solution_curve`` follows them and seeds the polish.
"""
from __future__ import annotations

import functools
import itertools
from typing import Callable

import numpy as np

from trajplan_ros.planning.objective import Objective

__all__ = ['Linearisation', 'polish', 'settle']

_TIE = 1e-12
#: Weight of the total joint travel (rad) in the merit, beside omega R (rad): it decides only
#: between steps that leave the motion time as it is (ties, see ``polish``).
_TRAVEL_WEIGHT = 1e-6


@functools.lru_cache(maxsize=8)
def _pairs(m: int) -> tuple[np.ndarray, np.ndarray]:
    return np.triu_indices(m, 1)


@functools.lru_cache(maxsize=8)
def _vertex_sets(m: int, k: int) -> np.ndarray:
    """
    Return the sets of k + 1 pieces that can meet at a vertex of ``_vertex_minimax``.

    Pieces 0..m-1 are the joints' displacements tying with the largest, piece m the limit
    nearest to the candidate: sets of k + 1 ties, and sets of that limit and k ties.
    """
    ties = list(itertools.combinations(range(m), k + 1))
    bounded = [(m, *s) for s in itertools.combinations(range(m), k)]
    return np.array(ties + bounded)


def _vertex_minimax(b: np.ndarray, null: np.ndarray, scale: np.ndarray, gap_lo: np.ndarray,
                    gap_hi: np.ndarray, limit: np.ndarray) -> np.ndarray:
    """
    Return z (K, k) that minimises max_i scale_i |b_i + (z @ null)_i| within the limits.

    b: (K, m) displacements; null: (K, k, m) orthonormal rows; the step z @ null must stay
    within [gap_lo, gap_hi] (the joint limits) and ||z|| within ``limit``. The function is
    convex and piecewise linear, so its least value lies at a vertex where k + 1 pieces meet:
    joints tying with the largest displacement (each with the sign it has at z = 0), or the
    joint nearest to a limit on it and k tying. Every such set gives a vertex by one small
    linear solve (a tiny ridge keeps degenerate sets solvable; their vertices are judged like
    the others); the best one inside the limits (or z = 0) is taken, then shortened to the
    trust radius (which, by convexity, keeps it no worse than z = 0 and inside the limits).
    """
    k_count, k, m = null.shape
    sets = _vertex_sets(m, k)                                            # (C, k + 1)
    sign = np.where(b >= 0.0, 1.0, -1.0) * scale
    columns = np.swapaxes(null, 1, 2)                                    # (K, m, k)
    ties = np.concatenate((columns * sign[:, :, None], -np.ones((k_count, m, 1))), axis=2)
    rows_k = np.arange(k_count)
    wall = np.argmin(np.minimum(gap_hi, -gap_lo), axis=1)                # the nearest limit
    bound = np.where(gap_hi < -gap_lo, gap_hi, gap_lo)[rows_k, wall]
    walls = np.concatenate((columns[rows_k, wall], np.zeros((k_count, 1))), axis=1)
    rows = np.concatenate((ties, walls[:, None, :]), axis=1)             # (K, m + 1, k + 1)
    rhs = np.concatenate((-sign * b, bound[:, None]), axis=1)            # (K, m + 1)
    system, rhs = rows[:, sets], rhs[:, sets]                            # (K, C, k+1, k+1)
    z = np.linalg.solve(system + 1e-13 * np.eye(k + 1), rhs[..., None])[..., :k, 0]
    z = np.concatenate((np.zeros((k_count, 1, k)), z), axis=1)          # (K, C + 1, k)
    step = z @ null                                                      # (K, C + 1, m)
    usable = np.all((step >= gap_lo[:, None, :] - 1e-12)
                    & (step <= gap_hi[:, None, :] + 1e-12), axis=2)
    worst = np.max(np.abs(b[:, None, :] + step) * scale, axis=2)         # (K, C + 1)
    best = z[rows_k, np.argmin(np.where(usable, worst, np.inf), axis=1)]
    size = np.sqrt(np.einsum('kj,kj->k', best, best))
    return best * np.minimum(1.0, limit / np.maximum(size, 1e-300))[:, None]


def _roots(qa: np.ndarray, qb: np.ndarray, qc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the real roots of qa z^2 + qb z + qc = 0 (NaN where there are none), stably.

    Call inside np.errstate(divide="ignore", invalid="ignore").
    """
    disc = qb * qb - 4.0 * qa * qc
    q = -0.5 * (qb + np.copysign(np.sqrt(disc), qb))
    flat = np.abs(qa) <= 1e-14 * (np.abs(qb) + 1e-300)
    return np.where(flat, -qc / qb, q / qa), np.where(flat, np.nan, qc / q)


def _line_minimax(b: np.ndarray, n: np.ndarray, a: np.ndarray, zlo: np.ndarray,
                  zhi: np.ndarray) -> np.ndarray:
    """
    Return the z in [zlo, zhi] that minimises max_i |b_i + n_i z + a_i z^2|.

    Ties go to the least total travel. b, n, a: (K, m); zlo, zhi: (K,). Returns z (K,).
    """
    iu, ju = _pairs(b.shape[1])
    bt, nt, at = b.T, n.T, a.T                                         # (m, K): fast broadcasting
    # |q_i| = |q_j| where q_i - q_j = 0 or q_i + q_j = 0; zeros of q_i; all as quadratics
    qa = np.concatenate((at[iu] - at[ju], at[iu] + at[ju], at))
    qb = np.concatenate((nt[iu] - nt[ju], nt[iu] + nt[ju], nt))
    qc = np.concatenate((bt[iu] - bt[ju], bt[iu] + bt[ju], bt))
    side = np.where(bt != 0.0, np.sign(bt), np.sign(nt))      # the signs of the q_i at z = 0
    with np.errstate(divide='ignore', invalid='ignore'):
        # vertices, zeros, stationary points of each |q_i| and of the total travel, the bounds
        least_travel = -(side * nt).sum(axis=0) / (2.0 * (side * at).sum(axis=0))
        cand = np.concatenate((*_roots(qa, qb, qc), -nt / (2.0 * at), least_travel[None],
                               zlo[None], zhi[None], np.zeros((1, b.shape[0]))))  # (C, K)
    cand = np.clip(np.where(np.isfinite(cand), cand, 0.0), zlo, zhi)
    d = np.abs(bt[:, None, :] + (nt[:, None, :] + at[:, None, :] * cand) * cand)   # (m, C, K)
    worst = functools.reduce(np.maximum, d)      # faster than reductions over a short axis 0
    total = functools.reduce(np.add, d)
    total = np.where(worst <= worst.min(axis=0) + _TIE, total, np.inf)
    return cand[np.argmin(total, axis=0), np.arange(b.shape[0])]


def _inverse(m: np.ndarray) -> np.ndarray:
    """
    Return the inverses of symmetric matrices (K, s, s).

    The adjugate formula for s = 3 (the position constraints; several times cheaper than LAPACK
    on small batches), np.linalg.inv otherwise.
    """
    if m.shape[1] != 3:
        return np.linalg.inv(m)
    a, b, c, _, d, e, _, _, f = m.reshape(-1, 9).T
    cof = (d * f - e * e, c * e - b * f, b * e - c * d,
           a * f - c * c, b * c - a * e, a * d - b * b)
    inv_det = 1.0 / (a * cof[0] + b * cof[1] + c * cof[2])
    full = np.array([cof[i] for i in (0, 1, 2, 1, 3, 4, 2, 4, 5)])
    return (full * inv_det).T.reshape(-1, 3, 3)


def _residuals(obj: Objective, x: np.ndarray) -> np.ndarray:
    return obj.residuals(*obj.tool(x))


class Linearisation:
    """
    The constraints c(x) linearised at K candidates x, with what a polish step needs.

    That is c, the merit, a pseudo-inverse of the constraint Jacobian J, a basis of its null
    space and, along each null direction n, half the curvature of the solution set:
    x''/2 = -J^+ c''/2, with c'' the exact second derivative of c along n
    (``ToolJacobian.curvature``).

    The pseudo-inverse comes from the damped normal equations, J^T (J J^T + mu I)^-1 (a few
    small matrix products, much cheaper than an SVD per step and well behaved near
    singularities); with one null direction (the usual case) it is the largest column of the
    projector I - J^+ J. ``curvature=False`` leaves the curvature out (zero), for speed.
    """

    def __init__(self, obj: Objective, x: np.ndarray, weight: float,
                 curvature: bool = True) -> None:
        d = obj.tool_jacobian(x)
        self.c = obj.residuals(d.p, d.u)
        self.time = obj.motion_time(x)
        self.error = obj.errors(d.p, d.u)
        travel = np.abs(x - obj.start[: obj.arm.planned]).sum(axis=1)
        self.merit = (self.time * obj.omega + _TRAVEL_WEIGHT * travel
                      + weight * np.sqrt(np.einsum('kr,kr->k', self.c, self.c)))
        jac = (np.concatenate((d.jp, obj.ray_basis[1:] @ d.ju), axis=1) if obj.radial
               else d.jp)
        k, rows, dim = jac.shape
        jt = np.swapaxes(jac, 1, 2)
        gram = jac @ jt if rows <= dim else jt @ jac
        size = gram.shape[1]
        damp = 1e-12 * np.trace(gram, axis1=1, axis2=2)[:, None, None] + 1e-300
        inverse = _inverse(gram + damp * np.eye(size))
        self.pinv = jt @ inverse if rows <= dim else inverse @ jt          # (K, dim, rows)
        free = dim - rows
        if free <= 0:
            self.null = np.empty((k, 0, dim))
        else:
            projector = np.eye(dim) - self.pinv @ jac
            if free == 1:
                col = np.argmax(np.einsum('kij,kij->kj', projector, projector), axis=1)
                n = projector[np.arange(k), :, col]
                self.null = (n / np.sqrt(np.einsum('ki,ki->k', n, n))[:, None])[:, None, :]
            else:
                self.null = np.swapaxes(np.linalg.svd(projector)[0][:, :, :free], 1, 2)
        self.half_curv = np.zeros_like(self.null)
        for j in range(self.null.shape[1] if curvature else 0):
            p2, u2 = d.curvature(self.null[:, j, :])
            c2 = obj.linear_residuals(p2, u2)
            self.half_curv[:, j, :] = 0.5 * self.newton(c2)

    def newton(self, res: np.ndarray) -> np.ndarray:
        """Minimum-norm step dx with J dx = -res (least squares where J is not onto)."""
        return -(self.pinv @ res[:, :, None])[:, :, 0]

    def keep(self, other: 'Linearisation', mask: np.ndarray) -> None:
        """Take other's values where mask is true."""
        for name in ('c', 'time', 'error', 'merit', 'pinv', 'null', 'half_curv'):
            mine, theirs = getattr(self, name), getattr(other, name)
            mine[mask] = theirs[mask]


def _null_step(null: np.ndarray, base: np.ndarray, start: np.ndarray, scale: np.ndarray,
               lo: np.ndarray, hi: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """
    Return the step along the null space that lowers R most in the linear model, (K, m).

    ``base``: the candidates after the Newton step; ``scale``: omega / omega_i. The step is
    cut short where it would leave the joint limits (it stays within ``delta``).
    """
    z = _vertex_minimax(base - start, null, scale, lo - base, hi - base, delta)
    step = np.einsum('kj,kjm->km', z, null)
    with np.errstate(divide='ignore', invalid='ignore'):
        room = np.where(step > 0, (hi - base) / step,
                        np.where(step < 0, (lo - base) / step, np.inf))
    return step * np.clip(np.min(room, axis=1), 0.0, 1.0)[:, None]


def polish(obj: Objective, x: np.ndarray, *, max_steps: int = 30, trust: float = 0.5,
           enough: Callable[[np.ndarray, np.ndarray, np.ndarray], bool] | None = None
           ) -> np.ndarray:
    """
    Refine candidates x (K, planned) towards reached, least-motion-time joint goals.

    ``enough(time, error, active)``, if given, is asked after every step and ends the polish
    early when it returns True (each candidate's motion time, s, and constraint error, m, and
    whether its steps are still being accepted, not stalled by repeated rejections).
    """
    lo, hi, scale = obj.lower, obj.upper, obj.time_scale
    start = obj.start[: obj.arm.planned]
    x = np.clip(np.array(x, dtype=float, ndmin=2), lo, hi)
    k = x.shape[0]
    # Penalty on |c| (metres, and the dimensionless axis residual): larger than any Lagrange
    # multiplier of this problem, so that the merit's minimum is the constrained one.
    weight = 1e3 / obj.arm.reach
    here = Linearisation(obj, x, weight)
    delta = np.full(k, trust)
    live = np.ones(k, dtype=bool)
    for _ in range(max_steps):
        step = here.newton(here.c)
        size = np.sqrt(np.einsum('km,km->k', step, step))
        step *= np.minimum(1.0, delta / np.maximum(size, 1e-300))[:, None]
        base = x + step
        if here.null.shape[1] > 1:          # a set of solutions of 2 or more dimensions
            base = base + _null_step(here.null, base, start, scale, lo, hi, delta)
        for j in range(here.null.shape[1]):
            direction, half_curv = here.null[:, j, :], here.half_curv[:, j, :]
            with np.errstate(divide='ignore', invalid='ignore'):       # the joint limits along z
                a_lo, a_hi = (lo - base) / direction, (hi - base) / direction
            moving = np.abs(direction) > 1e-15
            zlo = functools.reduce(
                np.maximum, np.where(moving, np.fmin(a_lo, a_hi), -np.inf).T, -delta)
            zhi = functools.reduce(
                np.minimum, np.where(moving, np.fmax(a_lo, a_hi), np.inf).T, delta)
            zhi = np.maximum(zhi, zlo)
            z = _line_minimax((base - start) * scale, direction * scale, half_curv * scale,
                              zlo, zhi)[:, None]
            base = base + (direction + half_curv * z) * z
        trial = np.clip(base, lo, hi)
        # second-order correction
        trial = np.clip(trial + here.newton(_residuals(obj, trial)), lo, hi)
        there = Linearisation(obj, trial, weight)
        moved = np.einsum('km,km->k', trial - x, trial - x)
        accept = live & (there.merit < here.merit)
        x[accept] = trial[accept]
        here.keep(there, accept)
        delta = np.where(accept, np.minimum(2 * delta, trust), delta / 2)
        live &= (moved > 1e-26) & (delta > 1e-13)
        if not live.any() or (enough is not None
                              and enough(here.time, here.error, delta >= trust / 5)):
            break
    return x


def settle(obj: Objective, x: np.ndarray, below: float, steps: int = 3) -> np.ndarray:
    """
    Return candidates x (K, planned) after Newton steps on the constraints alone.

    Only candidates with an error between ``below`` and 1e-2 of the reach take the steps, and
    each step is kept where it lowers the error. Near a singular solution (an elbow almost
    straight) the polish's merit, R + W |c|, can have its least value a little off the
    solutions, where the constraints' multipliers outgrow W; a few plain Newton steps from
    there settle on the solution.
    """
    x = np.clip(np.array(x, dtype=float, ndmin=2), obj.lower, obj.upper)
    error = obj.errors(*obj.tool(x))
    near = (error > below) & (error < 1e-2 * obj.arm.reach)
    if not near.any():
        return x
    here = Linearisation(obj, x[near], 1.0, curvature=False)
    for _ in range(steps):
        trial = np.clip(x[near] + here.newton(here.c), obj.lower, obj.upper)
        there = Linearisation(obj, trial, 1.0, curvature=False)
        better = there.error < here.error
        x[np.flatnonzero(near)[better]] = trial[better]
        here.keep(there, better)
    return x
