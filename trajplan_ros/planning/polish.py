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
travel at the same R. That makes plans repeatable.

With k >= 2 null directions (a 5- to 7-joint arm: the solutions form a k-dimensional set) the
line searches are replaced by one step of sequential quadratic programming on the model
x(z) = x + z N + z^T Q z of the solutions (Q from the second derivatives along every pair of
null directions): each candidate active set (the joints tying with the largest displacement,
chosen among the k + 2 largest, with any of the k nearest joint limits) gives a step: a
vertex set (k + 1 pieces) by its equations, a smaller one by its KKT system, both in closed
form where they are small (up to 3x3: numpy's batched LAPACK calls cost more than the
arithmetic at these sizes); the best on the model wins (``_active_set_minimax``). Near a
minimum that is
Newton's method on the right active set: it converges in a few steps where a coordinate
descent along the null directions stalls on the ridge where joints tie. Ties are then broken
only by the merit's travel term and by ``iepso._fastest`` among the candidates.

A trust radius, a second-order correction (chord Newton steps, each within the trust radius:
near a singular pose a chord step can be far longer than the step it corrects, and a
candidate whose every trial is such a leap never moves) and the merit make the steps safe.

Being local, the polish cannot see a faster solution elsewhere on the curve of solutions
through its answer, or on another curve; ``solution_curve`` follows them and seeds the polish.
"""
from __future__ import annotations

import functools
import itertools
from typing import Callable, NamedTuple

import numpy as np

from trajplan_ros.kinematics.arm import ToolJacobian
from trajplan_ros.planning.linearisation import line_searches, linearise, minimum_norm_steps
from trajplan_ros.planning.objective import Objective

__all__ = ['Linearisation', 'polish', 'settle']

_TIE = 1e-12
#: The active sets of ``_active_set_minimax`` tie the largest displacement with others among
#: the k + _LARGEST largest, and include any of the k nearest limits (a vertex has k + 1
#: pieces, at least one a joint's displacement: up to k can be limits; with two limits only,
#: the Panda missed optima with one joint at the motion time and three on a limit).
_LARGEST = 2
#: On sets of 2+ dimensions: chord steps of the second-order correction, and the rejections
#: in a row after which a candidate with an error (m) at most _CONVERGED_ERROR counts as
#: converged and leaves the batch.
_CHORD_STEPS = 3
_STALLED = 5
_CONVERGED_ERROR = 1e-9
#: Trust radius (rad) below which a candidate has converged: the motion time it could still
#: gain is of the order of this radius over omega.
_SMALLEST_RADIUS = 1e-9
#: Weight of the total joint travel (rad) in the merit, beside omega R (rad): it decides only
#: between steps that leave the motion time as it is (ties, see ``polish``).
_TRAVEL_WEIGHT = 1e-6


@functools.lru_cache(maxsize=16)
def _eye(n: int) -> np.ndarray:
    eye = np.eye(n)
    eye.flags.writeable = False
    return eye


@functools.lru_cache(maxsize=8)
def _pairs(m: int) -> tuple[np.ndarray, np.ndarray]:
    return np.triu_indices(m, 1)


class _ActiveSets(NamedTuple):
    """The active sets that ``_active_set_minimax`` tries (``_active_sets``)."""

    pieces: np.ndarray      # (C, k + 1): the pieces of each set
    vertex: np.ndarray      # (C,): the sets of k + 1 pieces, with no unused slot
    clashes: np.ndarray     # (r k, C): 1 where the set holds joint piece t and limit w, at
    #                         row t k + w (a set that ties a joint it holds at a limit)
    r: int                  # pieces 0..r-1 are joints' displacements (ties), r + k unused


@functools.lru_cache(maxsize=16)
def _active_sets(r: int, k: int, vertex_only: bool = False) -> _ActiveSets:
    """
    Return the active sets that ``_active_set_minimax`` tries (``_ActiveSets``).

    Pieces 0..r-1 are the r largest joints' displacements, tying with the largest, pieces r to
    r + k - 1 the k limits nearest to the candidate, and r + k an unused slot. Every set of 1
    to k + 1 joints that holds the largest (near a minimum the
    tying joints are the largest; away from one, a step that lowers the largest is what
    counts), with any of those limits, at most k + 1 pieces in all; with ``vertex_only``, only
    the sets of k + 1 pieces.
    """
    unused = r + k
    walls = [w for n in range(k + 1) for w in itertools.combinations(range(r, unused), n)]
    sets = [(*s, *w, *([unused] * (k + 1 - j - len(w))))
            for j in range(1, k + 2) for w in walls if j + len(w) <= k + 1
            for s in itertools.combinations(range(r), j) if s[0] == 0]
    pieces = np.array([s for s in sets if not vertex_only or unused not in s])
    clashes = np.array([[t in s and r + w in s for s in pieces.tolist()]
                        for t in range(r) for w in range(k)], dtype=float)
    return _ActiveSets(pieces, ~(pieces == unused).any(axis=1), clashes, r)


def _pieces(b: np.ndarray, null: np.ndarray, quad: np.ndarray, scale: np.ndarray,
            gap_lo: np.ndarray, gap_hi: np.ndarray, r: int
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Return the pieces of ``_active_sets`` per candidate: gradients, Hessians, KKT right sides.

    Pieces: the r largest scaled displacements, each with its sign (g z - t = -e, e its size at
    z = 0), the k nearest limits (n z = the gap to the limit), an unused slot (zeros).
    Gradients (K, P, k), Hessians (K, k, k, P), right sides (K, P), and the joint of each
    piece (K, P; -1 for the unused slot), with P = r + k + 1 pieces.
    """
    k_count, k, m = null.shape
    rows_k = np.arange(k_count)[:, None]
    sign = np.where(b >= 0.0, 1.0, -1.0) * scale
    size = np.abs(b) * scale
    top = np.argsort(-size, axis=1)[:, :r]                                  # (K, r)
    walls = np.argsort(np.minimum(gap_hi, -gap_lo), axis=1)[:, :k]          # (K, k)
    joint = np.concatenate((top, walls, np.full((k_count, 1), -1)), axis=1)
    # each piece's sign: the joint's for a displacement, 1 for a limit, 0 for the unused slot
    weight = np.concatenate((sign[rows_k, top], np.ones((k_count, k)),
                             np.zeros((k_count, 1))), axis=1)
    grad = np.swapaxes(null, 1, 2)[rows_k, joint] * weight[:, :, None]
    hess = (np.take_along_axis(quad, joint[:, None, None, :], axis=3)
            * (2.0 * weight[:, None, None]))
    near = np.where(gap_hi < -gap_lo, gap_hi, gap_lo)[rows_k, walls]
    rhs = np.concatenate((-size[rows_k, top], near, np.zeros((k_count, 1))), axis=1)
    return grad, hess, rhs, joint


def _sqp_steps(grad: np.ndarray, hess: np.ndarray, rhs: np.ndarray, joint: np.ndarray,
               sets: _ActiveSets) -> np.ndarray:
    """
    Return the SQP step z (K, C, k) of every active set (``_active_set_minimax``).

    The problem: min t subject to the set's pieces g z - t = -e (ties) and n z = gap (limits).
    Its first piece is the largest joint's (a tie), so t = g_0 z + e_0, and what is left is in
    z alone: (g_s - tie_s g_0) z = rhs_s - tie_s rhs_0 for the other pieces s. A set of k + 1
    pieces (a vertex: no unused slot) fixes z by those k equations alone (``_vertex_steps``);
    a smaller one takes the Hessian of the Lagrangian into account (``_kkt_steps``). A set that
    ties a joint it also holds at a limit has no step (z = 0). On sets of k >= 2 dimensions.
    """
    pieces, vertex, clashes, r = sets
    k = grad.shape[2]
    at_limit = joint[:, :r, None] == joint[:, None, r: r + k]               # (K, r, k)
    clash = at_limit.reshape(len(joint), -1) @ clashes > 0.0                # (K, C)
    # each piece's equation in z alone, (K, P, k) and (K, P) (zero for piece 0 and
    # for the unused slot)
    tie = (np.arange(rhs.shape[1]) < r).astype(float)
    rows = grad - tie[:, None] * grad[:, :1]
    values = rhs - tie * rhs[:, :1]
    others = pieces[:, 1:]
    z = np.empty(clash.shape + grad.shape[2:])
    z[:, vertex] = _vertex_steps(rows[:, others[vertex]], values[:, others[vertex]],
                                 clash[:, vertex])
    if not vertex.all():
        z[:, ~vertex] = _kkt_steps(hess, grad[:, 0], rows, values, pieces[~vertex], r + k,
                                   tie, clash[:, ~vertex])
    return np.where(np.isfinite(z).all(axis=2, keepdims=True), z, 0.0)


def _vertex_steps(rows: np.ndarray, values: np.ndarray, clash: np.ndarray) -> np.ndarray:
    """Return z (K, V, k) of vertex sets: rows z = values (``_sqp_steps``); clash sets: 0."""
    k = rows.shape[-1]
    rows = np.where(clash[..., None, None], np.eye(k), rows)
    return _solve_small(rows + 1e-13 * np.eye(k), np.where(clash[..., None], 0.0, values))


def _kkt_steps(hess: np.ndarray, g0: np.ndarray, rows: np.ndarray, values: np.ndarray,
               pieces: np.ndarray, unused: int, tie: np.ndarray, clash: np.ndarray
               ) -> np.ndarray:
    """
    Return z (K, C, k) of the sets ``pieces`` (C, p) with ``unused`` slots (``_sqp_steps``).

    min g_0 z + z^T H z / 2 subject to the set's other pieces' ``rows`` z = ``values`` (at most
    k - 1; rows and values by piece, ``tie`` by piece), with H the Hessian of the Lagrangian
    sum_s y_s H_s taken at least-squares multipliers (min |sum_s y_s g_s| with the ties' y
    summing to 1) and a ridge of 1e-13: with no row the stationary point of the largest
    joint's displacement; with k - 1 rows (k <= 3) along the line they leave, in closed form;
    else by the KKT system. ``clash`` sets get z = 0.
    """
    k = g0.shape[-1]
    others = pieces[:, 1:k]                                                 # (C, k - 1)
    used = others != unused
    # the other pieces' multipliers: least |g_0 + rows^T y| (rows = g_s - tie_s g_0)
    gram = _dot(rows[:, :, None, :], rows[:, None, :, :])[:, others[:, :, None], others[:, None]]
    ridge = 1e-12 * sum(gram[..., i, i] for i in range(k - 1)) + 1e-300
    gram = gram + (ridge[..., None, None] + ~used[:, :, None]) * np.eye(k - 1)
    y = _solve_small(gram, -_dot(rows, g0[:, None, :])[:, others])
    weights = [1.0 - _dot(tie[others], y)] + [y[..., s] for s in range(k - 1)]
    h = np.moveaxis(hess, 3, 1)[:, pieces[:, :k]]                           # (K, C, k, k, k)
    lagrangian = sum(w[..., None, None] * h[:, :, s] for s, w in enumerate(weights))
    lagrangian = lagrangian + 1e-13 * np.eye(k)
    rows, values = rows[:, others], values[:, others]                       # (K, C, k - 1, k)
    g0 = np.broadcast_to(g0[:, None, :], (len(g0), len(pieces), k))
    count = used.sum(axis=1)
    z = np.empty(g0.shape)
    for c in np.unique(count):
        sel = count == c
        hl, gs, rs, vs = lagrangian[:, sel], g0[:, sel], rows[:, sel, :c], values[:, sel, :c]
        if c == 0:
            z[:, sel] = _solve_small(hl, -gs)
        elif c == k - 1 and k <= 3:         # the least-norm solution plus s times the line's n
            n = (np.stack((-rs[..., 0, 1], rs[..., 0, 0]), axis=-1) if k == 2
                 else _cross(rs[..., 0, :], rs[..., 1, :]))
            base = _dot(np.swapaxes(rs, -1, -2),
                        _solve_small(gram[:, sel, :c, :c], vs)[..., None, :])
            hn = _dot(hl, n[..., None, :])
            with np.errstate(all='ignore'):
                s = -(_dot(gs, n) + _dot(hn, base)) / _dot(hn, n)
            z[:, sel] = base + s[..., None] * n
        else:
            border = np.zeros(gs.shape[:2] + (k + c, k + c))
            border[..., :k, :k] = hl
            border[..., k:, :k] = rs
            border[..., :k, k:] = np.swapaxes(rs, -1, -2)
            border[..., k:, k:] = 1e-13 * np.eye(c)
            z[:, sel] = _solve_small(border, np.concatenate((-gs, vs), axis=-1))[..., :k]
    return np.where(clash[..., None] | ~np.isfinite(z), 0.0, z)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Return the sums of products over the last axis (of a few entries), as a fold."""
    return functools.reduce(np.add, [a[..., i] * b[..., i] for i in range(a.shape[-1])])


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Return the cross products of 3-vectors (..., 3)."""
    return np.stack((a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]), axis=-1)


def _solve_small(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """
    Return x with a x = b, for a (..., n, n) and b (..., n).

    Closed forms for n <= 3 (many tiny LAPACK calls cost more); ``_solve`` otherwise.
    """
    n = a.shape[-1]
    if n > 3:
        return _solve(a, b[..., None])[..., 0]
    with np.errstate(all='ignore'):
        if n == 1:
            return b / a[..., 0]
        if n == 2:
            det = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]
            return np.stack((a[..., 1, 1] * b[..., 0] - a[..., 0, 1] * b[..., 1],
                             a[..., 0, 0] * b[..., 1] - a[..., 1, 0] * b[..., 0]),
                            axis=-1) / det[..., None]
        # x = sum_s b_s (a_{s+1} x a_{s+2}) / det, over the rows a_s
        c = _cross(a[..., [1, 2, 0], :], a[..., [2, 0, 1], :])
        det = _dot(a[..., 0, :], c[..., 0, :])
        return _dot(np.swapaxes(c, -1, -2), b[..., None, :]) / det[..., None]


def _solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Return np.linalg.solve(a, b); least squares for all when one matrix is exactly singular."""
    with np.errstate(all='ignore'):
        try:
            return np.linalg.solve(a, b)
        except np.linalg.LinAlgError:
            return np.linalg.pinv(a) @ b


def _active_set_minimax(b: np.ndarray, null: np.ndarray, quad: np.ndarray, scale: np.ndarray,
                        gap_lo: np.ndarray, gap_hi: np.ndarray, limit: np.ndarray,
                        vertex_only: bool = False) -> np.ndarray:
    """
    Return z (K, k) that minimises max_i scale_i |d_i(z)| on the quadratic model of the solutions.

    d(z) = b + z N + z^T Q z (b (K, m): displacements; ``null`` (K, k, m): N, orthonormal rows;
    ``quad`` (K, k, k, m): Q, half the second derivative of the solutions). The steps must keep
    the joints within [gap_lo, gap_hi] and ||z|| within ``limit``. Each active set (joints tying
    with the largest displacement, each with its sign at z = 0, and any of the k nearest
    limits) gives the SQP step of min t subject to those pieces = t (the limits
    reached), ``_sqp_steps``. With k + 1 pieces that is a vertex of the linear model, whatever
    the Hessian. Every step is shortened to the trust radius and judged on the model: its linear
    part must keep within the limits, and where the curvature term passes a limit the joint is
    clipped to it; the best, or z = 0, wins. ``vertex_only``: the vertices alone (cheaper).
    """
    k_count, k, m = null.shape
    r = min(m, k + _LARGEST)
    z = _sqp_steps(*_pieces(b, null, quad, scale, gap_lo, gap_hi, r),
                   _active_sets(r, k, vertex_only))
    z = np.concatenate((np.zeros((k_count, 1, k)), z), axis=1)            # (K, C + 1, k)
    z = _within(z, limit[:, None])
    linear = z @ null
    pairs = (z[..., :, None] * z[..., None, :]).reshape(k_count, -1, k * k)
    step = linear + pairs @ quad.reshape(k_count, k * k, m)
    lo, hi = gap_lo[:, None, :], gap_hi[:, None, :]
    # folds over the few joints: several times faster than reductions over a short last axis
    usable = functools.reduce(np.logical_and,
                              np.moveaxis((linear >= lo - 1e-12) & (linear <= hi + 1e-12), 2, 0))
    moved = np.abs(b[:, None, :] + np.clip(step, lo, hi)) * scale
    worst = functools.reduce(np.maximum, np.moveaxis(moved, 2, 0))
    return z[np.arange(k_count), np.argmin(np.where(usable, worst, np.inf), axis=1)]


def _residuals(obj: Objective, x: np.ndarray) -> np.ndarray:
    return obj.residuals(*obj.tool(x))


class Linearisation:
    """
    The constraints c(x) linearised at K candidates x, with what a polish step needs.

    That is c, the motion time, the error, the merit, a pseudo-inverse of the constraint
    Jacobian J, a basis of its null space and ``quad`` (K, k, k, planned): half the second
    derivatives of the solution set along every pair of null directions, on its diagonal
    x''/2 = -J^+ c''/2 along each direction n, with c'' the exact second derivative of c along n
    (from ``ToolJacobian.hessian``). One compiled kernel computes them
    (``linearisation.linearise``).

    The pseudo-inverse comes from the damped normal equations, J^T (J J^T + mu I)^-1 (a few
    small matrix products, much cheaper than an SVD per step and well behaved near
    singularities); with one null direction (the usual case) it is the largest column of the
    projector I - J^+ J; with more, the columns of a complete QR of J^T beyond its row count
    (where J loses rank, that basis misses a null direction). The pairs off the diagonal of
    ``quad`` serve the SQP step of two or more null directions (``_active_set_minimax``).
    ``newton_only`` leaves the null space and the curvature out (both empty): all a Newton
    step needs, for speed.
    """

    def __init__(self, obj: Objective, x: np.ndarray, weight: float,
                 newton_only: bool = False) -> None:
        x = np.ascontiguousarray(x, dtype=float)
        d: ToolJacobian = obj.tool_jacobian(x)
        planned, across = x.shape[1], obj.across_basis
        free = 0 if newton_only else max(planned - 3 - len(across), 0)
        hessian = d.hessian() if free else np.empty((0, planned, planned, 2, 3))
        self.c, self.time, self.merit, self.pinv, self.null, self.quad = linearise(
            d.rows, hessian, x, np.ascontiguousarray(obj.planned_start),
            np.ascontiguousarray(obj.time_scale), obj.omega, np.ascontiguousarray(obj.goal),
            np.ascontiguousarray(across), _TRAVEL_WEIGHT, float(weight), free)
        self.error = obj.errors(d.p, d.u)

    def newton(self, res: np.ndarray, radius: np.ndarray | None = None) -> np.ndarray:
        """
        Return minimum-norm steps dx (K, planned): J dx = -res (least squares off its range).

        With ``radius`` (K,), each shortened to at most its radius.
        """
        if radius is None:
            radius = np.full(len(self.pinv), np.inf)
        return minimum_norm_steps(self.pinv, np.ascontiguousarray(res, dtype=float),
                                  np.ascontiguousarray(radius, dtype=float))

    _FIELDS = ('c', 'time', 'error', 'merit', 'pinv', 'null', 'quad')

    def keep(self, other: 'Linearisation', mask: np.ndarray) -> None:
        """Take other's values where mask is true."""
        for name in self._FIELDS:
            mine = getattr(self, name)
            np.copyto(mine, getattr(other, name),
                      where=mask.reshape(mask.shape + (1,) * (mine.ndim - 1)))

    def take(self, mask: np.ndarray) -> None:
        """Keep only the candidates where mask is true."""
        for name in self._FIELDS:
            setattr(self, name, getattr(self, name)[mask])


def _null_step(null: np.ndarray, quad: np.ndarray, base: np.ndarray, start: np.ndarray,
               scale: np.ndarray, lo: np.ndarray, hi: np.ndarray, delta: np.ndarray,
               vertex_only: bool) -> np.ndarray:
    """
    Return the candidates ``base`` (K, m) moved along the solutions to lower R (the SQP step).

    ``base``: the candidates after the Newton step; ``scale``: omega / omega_i; ``delta``: the
    trust radii. The step is the quadratic model's (``_active_set_minimax``), clipped to the
    joint limits.
    """
    z = _active_set_minimax(base - start, null, quad, scale, lo - base, hi - base, delta,
                            vertex_only)
    step = np.einsum('kj,kjm->km', z, null) + np.einsum('ka,kabm,kb->km', z, quad, z)
    return np.clip(base + step, lo, hi)


def _line_searches(here: Linearisation, base: np.ndarray, start: np.ndarray,
                   scale: np.ndarray, lo: np.ndarray, hi: np.ndarray, radius: np.ndarray
                   ) -> np.ndarray:
    """
    Return ``base`` moved by the line searches along each null direction in turn.

    Each is the exact minimax of the joints' displacements, parabolas in the step, ties going
    to the least total travel (``linearisation.line_searches``, compiled).
    """
    return line_searches(here.null, here.quad, np.ascontiguousarray(base, dtype=float),
                         np.ascontiguousarray(start), np.ascontiguousarray(scale),
                         np.ascontiguousarray(lo), np.ascontiguousarray(hi),
                         np.ascontiguousarray(radius, dtype=float), _TIE)


def _trial(obj: Objective, here: Linearisation, x: np.ndarray, radius: np.ndarray,
           wide: bool, vertex_only: bool) -> np.ndarray:
    """
    Return the polish's trial points from candidates x (K, planned) and their linearisation.

    The Newton step to the solutions (within the trust radii), the step along them (the line
    searches, or on sets of 2+ dimensions the SQP step), the limits, then the second-order
    correction: chord Newton steps with the Jacobian at x, each within the trust radius.
    """
    lo, hi, scale = obj.lower, obj.upper, obj.time_scale
    start = obj.planned_start
    base = x + here.newton(here.c, radius)
    if wide:
        base = _null_step(here.null, here.quad, base, start, scale, lo, hi, radius,
                          vertex_only)
    else:
        base = _line_searches(here, base, start, scale, lo, hi, radius)
    trial = np.clip(base, lo, hi)
    for _ in range(_CHORD_STEPS if wide else 1):
        trial = np.clip(trial + here.newton(_residuals(obj, trial), radius), lo, hi)
    return trial


def _within(step: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Return the steps (..., m) shortened to at most ``radius`` (...) each."""
    size = np.sqrt(np.einsum('...m,...m->...', step, step))
    return step * np.minimum(1.0, radius / np.maximum(size, 1e-300))[..., None]


def polish(obj: Objective, x: np.ndarray, *, max_steps: int = 30,
           trust: float | np.ndarray = 0.5,
           enough: Callable[[np.ndarray, np.ndarray, np.ndarray], bool] | None = None,
           prune: tuple[int, int] | None = None, vertex_steps: int = 0) -> np.ndarray:
    """
    Refine candidates x (K, planned) towards reached, least-motion-time joint goals.

    ``enough(time, error, radius)``, if given, is asked after every step and ends the polish
    early when it returns True (each candidate's motion time, s, constraint error, m, and trust
    radius, rad: halved or less by each rejected step, doubled by each accepted one up to
    ``trust``, one for all candidates or one each, and 0 once converged). A candidate has
    converged when its radius falls to ``_SMALLEST_RADIUS``; on sets of 2+ dimensions also
    when it is on the solutions and its steps were rejected ``_STALLED`` times in a row (it
    then takes no more steps). ``prune`` = (steps, count): after that many steps only the
    ``count`` candidates of least merit that have not converged take more steps; the others
    are returned where they are. On sets of 2+ dimensions the first ``vertex_steps`` SQP
    steps try only the vertex sets of ``_active_set_minimax`` (far from a minimum, the step
    that counts).
    """
    x = np.clip(np.array(x, dtype=float, ndmin=2), obj.lower, obj.upper)
    k = x.shape[0]
    weight = 1e3 / obj.arm.reach    # on |c|: above any Lagrange multiplier here (exact penalty)
    here = Linearisation(obj, x, weight)
    wide = here.null.shape[1] > 1           # a set of solutions of 2 or more dimensions
    trust = np.broadcast_to(np.asarray(trust, dtype=float), (k,))
    delta = trust.copy()                    # the trust radii; 0 once converged
    rows = np.arange(k)                     # the candidates that take steps
    rejected = np.zeros(k, dtype=int)
    time, error = here.time.copy(), here.error.copy()
    for step in range(max_steps):
        if prune is not None and step == prune[0] and len(rows) > prune[1]:
            moving = np.where(delta[rows] > 0.0, here.merit, np.inf)      # converged: done
            best = np.isin(np.arange(len(rows)), np.argsort(moving, kind='stable')[: prune[1]])
            delta[rows[~best]] = 0.0
            rows = rows[best]
            here.take(best)
        radius = delta[rows]
        trial = _trial(obj, here, x[rows], radius, wide, step < vertex_steps)
        there = Linearisation(obj, trial, weight)
        moved = np.sqrt(np.einsum('km,km->k', trial - x[rows], trial - x[rows]))
        accept = (radius > 0.0) & (there.merit < here.merit)
        x[rows[accept]] = trial[accept]
        here.keep(there, accept)
        # a rejected step shrinks the radius below its own length: the same trial again
        # would be rejected again
        delta[rows] = np.where(accept, np.minimum(2 * radius, trust[rows]),
                               np.minimum(radius, moved) / 2)
        converged = delta[rows] <= _SMALLEST_RADIUS
        time[rows], error[rows] = here.time, here.error
        if wide:        # on the solutions and rejected _STALLED times in a row: converged
            rejected[rows] = np.where(accept, 0, rejected[rows] + 1)
            converged |= (rejected[rows] >= _STALLED) & (here.error <= _CONVERGED_ERROR)
        delta[rows[converged]] = 0.0
        if wide:        # converged candidates leave the batch
            rows = rows[~converged]
            here.take(~converged)
        if not delta.any() or (enough is not None and enough(time, error, delta)):
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
    here = Linearisation(obj, x[near], 1.0, newton_only=True)
    for _ in range(steps):
        trial = np.clip(x[near] + here.newton(here.c), obj.lower, obj.upper)
        there = Linearisation(obj, trial, 1.0, newton_only=True)
        better = there.error < here.error
        x[np.flatnonzero(near)[better]] = trial[better]
        here.keep(there, better)
    return x
