# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The polish's constraints linearised, and its exact line minimax along the solutions, compiled.

``linearise`` linearises the constraints c(x) = 0 (reach, and with the axis held: the
residuals p - goal and the tool axes' components across their targets, ``Objective.residuals``)
at K candidates x, from the forward kinematics' first and second derivatives. With J the
Jacobian of c by the planned joints it returns:

- c, the motion time R (eq. 10) and the merit omega R + travel weight sum |x - start| + W |c|;
- the pseudo-inverse J^+ from the damped normal equations, J^T (J J^T + mu I)^-1 (or
  (J^T J + mu I)^-1 J^T with more rows than joints), mu = 1e-12 trace: a few small products,
  much cheaper than an SVD and well behaved near singularities;
- a basis N of the null space of J: with one null direction the largest column of the
  projector I - J^+ J, normalised; with more, the columns of a complete QR of J^T beyond its
  rows (Householder reflections as LAPACK's dgeqrf and dorgqr take them);
- Q (K, k, k, planned): half the second derivatives of the solutions along every pair of null
  directions, Q_ab = -J^+ c''_ab / 2 with c''_ab = n_a^T (d2c/dq2) n_b: moving by z along the
  null space, the solutions are x + z N + z^T Q z to second order.

``line_searches`` moves candidates along each null direction in turn by ``line_minimax``: the
exact minimiser over a line of the largest of the joints' displacements, each a parabola in the
step z, ties going to the least total travel.
"""
from __future__ import annotations

import numpy as np

from trajplan_ros.kinematics.forward import column
from trajplan_ros.kinematics.jit import inlined_kernel, kernel
from trajplan_ros.motion.time_law import joint_time, TimeLaw

__all__ = ['line_minimax', 'line_searches', 'linearise', 'minimum_norm_steps', 'solution_model']


@kernel
def invert_symmetric(m: np.ndarray, out: np.ndarray) -> None:
    """
    Put the inverse of a symmetric positive definite matrix m (s, s) into ``out`` (s, s).

    The adjugate for s = 3 (the position constraints), else Gauss-Jordan elimination with
    partial pivoting (which overwrites m).
    """
    s = m.shape[0]
    if s == 3:
        a, b, c, d, e, f = m[0, 0], m[0, 1], m[0, 2], m[1, 1], m[1, 2], m[2, 2]
        cof = (d * f - e * e, c * e - b * f, b * e - c * d,
               a * f - c * c, b * c - a * e, a * d - b * b)
        inv_det = np.divide(1.0, a * cof[0] + b * cof[1] + c * cof[2])
        out[0, 0] = cof[0] * inv_det
        out[0, 1] = out[1, 0] = cof[1] * inv_det
        out[0, 2] = out[2, 0] = cof[2] * inv_det
        out[1, 1] = cof[3] * inv_det
        out[1, 2] = out[2, 1] = cof[4] * inv_det
        out[2, 2] = cof[5] * inv_det
        return
    out[:] = 0.0
    for i in range(s):
        out[i, i] = 1.0
    for col in range(s):
        pivot = col
        for r in range(col + 1, s):
            if abs(m[r, col]) > abs(m[pivot, col]):
                pivot = r
        if pivot != col:
            for j in range(s):
                m[col, j], m[pivot, j] = m[pivot, j], m[col, j]
                out[col, j], out[pivot, j] = out[pivot, j], out[col, j]
        scale = np.divide(1.0, m[col, col])
        for j in range(s):
            m[col, j] *= scale
            out[col, j] *= scale
        for r in range(s):
            if r != col and m[r, col] != 0.0:
                f = m[r, col]
                for j in range(s):
                    m[r, j] -= f * m[col, j]
                    out[r, j] -= f * out[col, j]


@kernel
def complete_null_basis(a: np.ndarray, tau: np.ndarray, out: np.ndarray) -> None:
    """
    Put the columns of the complete QR of a (m, r), m > r, beyond r into ``out`` (m - r, m).

    Householder reflections H_i = I - tau_i v_i v_i^T as LAPACK's dgeqr2 (dlarfg: beta =
    -sign(alpha) |x|) and dorg2r take them: the columns are H_0 ... H_{r-1} e_j, j >= r. ``a``
    is overwritten by the reflectors, ``tau`` (r,) by their weights.
    """
    m, r = a.shape
    for i in range(r):
        tau[i] = 0.0
        alpha = a[i, i]
        xnorm = 0.0
        for t in range(i + 1, m):
            xnorm += a[t, i] * a[t, i]
        xnorm = np.sqrt(xnorm)
        if xnorm == 0.0:
            continue
        big, small = max(abs(alpha), xnorm), min(abs(alpha), xnorm)
        beta = -np.copysign(big * np.sqrt(1.0 + (small / big) ** 2), alpha)
        tau[i] = (beta - alpha) / beta
        shrink = 1.0 / (alpha - beta)
        for t in range(i + 1, m):
            a[t, i] *= shrink
        a[i, i] = 1.0                          # v = (1, a[i + 1:, i])
        for j in range(i + 1, r):              # the columns after i: C <- C - tau v (v^T C)
            w = 0.0
            for t in range(i, m):
                w += a[t, i] * a[t, j]
            w *= tau[i]
            for t in range(i, m):
                a[t, j] -= w * a[t, i]
        a[i, i] = beta
    for j in range(r, m):
        q = out[j - r]
        q[:] = 0.0
        q[j] = 1.0
        for i in range(r - 1, -1, -1):
            if tau[i] == 0.0:
                continue
            w = q[i]
            for t in range(i + 1, m):
                w += a[t, i] * q[t]
            w *= tau[i]
            q[i] -= w
            for t in range(i + 1, m):
                q[t] -= w * a[t, i]


@kernel
def residuals_and_jacobians(walk: np.ndarray, goal: np.ndarray, across: np.ndarray
                            ) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the residuals c (K, 3 + h) and their Jacobians J (K, 3 + h, planned).

    The residuals p - goal and, per row r of ``across`` (h, V - 1, 3), sum_t across[r, t] . a_t
    over the tool's axes a_t (u, then w); the Jacobian's columns dp/dq_i and the same sums of
    da_t/dq_i, from ``walk`` (V vectors; see ``linearise``).
    """
    vectors = across.shape[1] + 1
    count, held = walk.shape[1], across.shape[0]
    dim = (walk.shape[0] - vectors) // (vectors + 1)
    c, jac = np.empty((count, 3 + held)), np.empty((count, 3 + held, dim))
    for k in range(count):
        for a in range(3):
            c[k, a] = walk[0, k, a] - goal[a]
        for h in range(held):
            total = 0.0
            for t in range(1, vectors):
                for e in range(3):
                    total += across[h, t - 1, e] * walk[t, k, e]
            c[k, 3 + h] = total
        for i in range(dim):
            for a in range(3):
                jac[k, a, i] = walk[column(vectors, i, 0), k, a]
            for h in range(held):
                total = 0.0
                for t in range(1, vectors):
                    row = column(vectors, i, t)
                    for e in range(3):
                        total += across[h, t - 1, e] * walk[row, k, e]
                jac[k, 3 + h, i] = total
    return c, jac


@kernel
def damped_pseudo_inverses(jac: np.ndarray) -> np.ndarray:
    """
    Return J^+ (K, dim, rows) of each J in jac (K, rows, dim), by the damped normal equations.

    J^T (J J^T + mu I)^-1, or (J^T J + mu I)^-1 J^T with more rows than columns, mu = 1e-12
    trace + 1e-300.
    """
    count, rows, dim = jac.shape
    size = min(rows, dim)
    wide = rows <= dim                           # J J^T, else J^T J
    gram, inverse = np.empty((size, size)), np.empty((size, size))
    pinv = np.empty((count, dim, rows))
    for k in range(count):
        trace = 0.0
        for a in range(size):
            for b in range(a, size):
                total = 0.0
                if wide:
                    for i in range(dim):
                        total += jac[k, a, i] * jac[k, b, i]
                else:
                    for r in range(rows):
                        total += jac[k, r, a] * jac[k, r, b]
                gram[a, b] = gram[b, a] = total
            trace += gram[a, a]
        damp = 1e-12 * trace + 1e-300
        for a in range(size):
            gram[a, a] += damp
        invert_symmetric(gram, inverse)
        for i in range(dim):
            for r in range(rows):
                total = 0.0
                if wide:
                    for s in range(rows):
                        total += jac[k, s, i] * inverse[s, r]
                else:
                    for s in range(dim):
                        total += inverse[i, s] * jac[k, r, s]
                pinv[k, i, r] = total
    return pinv


@kernel
def null_bases(jac: np.ndarray, pinv: np.ndarray, nulls: int) -> np.ndarray:
    """
    Return a basis of the null space of each J (K, nulls, dim), orthonormal rows.

    One direction: the largest column of the projector I - J^+ J (the first of equals),
    normalised; more: the columns of a complete QR of J^T beyond its rows
    (``complete_null_basis``).
    """
    count, rows, dim = jac.shape
    null = np.zeros((count, nulls, dim))
    reflectors, tau = np.empty((dim, rows)), np.empty(rows)   # J^T, then its reflectors
    for k in range(count):
        if nulls > 1:
            reflectors[:] = jac[k].T
            complete_null_basis(reflectors, tau, null[k])
            continue
        best, best_size = 0, -1.0
        for j in range(dim):
            col_size = 0.0
            for i in range(dim):
                entry = (1.0 if i == j else 0.0)
                for r in range(rows):
                    entry -= pinv[k, i, r] * jac[k, r, j]
                col_size += entry * entry
            if col_size > best_size:
                best, best_size = j, col_size
        length = np.sqrt(best_size)
        for i in range(dim):
            entry = (1.0 if i == best else 0.0)
            for r in range(rows):
                entry -= pinv[k, i, r] * jac[k, r, best]
            null[k, 0, i] = np.divide(entry, length)
    return null


@kernel
def solutions_curvatures(hessian: np.ndarray, null: np.ndarray, pinv: np.ndarray,
                         across: np.ndarray) -> np.ndarray:
    """
    Return Q (K, k, k, dim): Q_ab = -J^+ c''_ab / 2, c''_ab = n_a^T (d2c/dq2) n_b.

    ``hessian`` (K, dim, dim, V, 3): the second derivatives of p and the axes, which the
    residuals map as ``residuals_and_jacobians`` does; ``null`` (K, k, dim): the null
    directions n_a.
    """
    count, nulls, dim = null.shape
    held, rows, vectors = across.shape[0], pinv.shape[2], hessian.shape[3]
    quad = np.zeros((count, nulls, nulls, dim))
    turn = np.empty((nulls, dim, vectors, 3))       # the Hessian times each n_b
    second, bent = np.empty(rows), np.empty((vectors, 3))
    for k in range(count):
        turn[:] = 0.0
        for b in range(nulls):
            for i in range(dim):
                for j in range(dim):
                    weight_j = null[k, b, j]
                    for t in range(vectors):
                        for e in range(3):
                            turn[b, i, t, e] += hessian[k, i, j, t, e] * weight_j
        for a in range(nulls):
            for b in range(a, nulls):
                for t in range(vectors):             # n_a^T H n_b of the point and each axis
                    for e in range(3):
                        total = 0.0
                        for i in range(dim):
                            total += null[k, a, i] * turn[b, i, t, e]
                        bent[t, e] = total
                for e in range(3):
                    second[e] = bent[0, e]
                for h in range(held):
                    total = 0.0
                    for t in range(1, vectors):
                        for e in range(3):
                            total += across[h, t - 1, e] * bent[t, e]
                    second[3 + h] = total
                for i in range(dim):
                    total = 0.0
                    for r in range(rows):
                        total += pinv[k, i, r] * second[r]
                    quad[k, a, b, i] = quad[k, b, a, i] = -0.5 * total
    return quad


@inlined_kernel
def linearise(walk: np.ndarray, hessian: np.ndarray, x: np.ndarray, start: np.ndarray,
              law: TimeLaw, omega: float, goal: np.ndarray, across: np.ndarray,
              travel_weight: float, weight: float, nulls: int
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                         np.ndarray]:
    """
    Return c, R, the merit, J^+, N and Q at candidates x (K, planned) (see the module).

    ``walk`` (V + (V + 1) planned, K, 3): p, the axes and per joint their derivatives and Z_i,
    and ``hessian`` (K, planned, planned, V, 3), as ``ToolJacobian`` gives them (the Hessian
    only with null directions); ``start``: per planned joint; ``law``: the joints' time laws;
    ``across`` (h, V - 1, 3): the components of the axes held (h = 0 in free mode);
    ``travel_weight`` and ``weight`` (W): the merit's weights of the travel and of |c|;
    ``nulls``: the null directions wanted (0, or the planned joints less the 3 + h residuals).
    Returns c (K, 3 + h), R (K,), merit (K,), J^+ (K, planned, 3 + h), N (K, nulls, planned)
    and Q (K, nulls, nulls, planned).
    """
    count, dim = x.shape
    c, jac = residuals_and_jacobians(walk, goal, across)
    time, merit = np.empty(count), np.empty(count)
    for k in range(count):                       # R (eq. 10) and the merit
        largest, travel, norm = 0.0, 0.0, 0.0
        for i in range(dim):
            moved = abs(x[k, i] - start[i])
            largest = max(largest, joint_time(law, i, moved))
            travel += moved
        for a in range(c.shape[1]):
            norm += c[k, a] * c[k, a]
        time[k] = largest
        merit[k] = time[k] * omega + travel_weight * travel + weight * np.sqrt(norm)
    pinv, null, quad = solution_model(jac, hessian, across, nulls)
    return c, time, merit, pinv, null, quad


@kernel
def solution_model(jac: np.ndarray, hessian: np.ndarray, across: np.ndarray, nulls: int
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return J^+, N and Q (see ``linearise``) from the Jacobians jac (K, 3 + h, planned)."""
    count, dim = jac.shape[0], jac.shape[2]
    pinv = damped_pseudo_inverses(jac)
    if nulls == 0:
        return pinv, np.zeros((count, 0, dim)), np.zeros((count, 0, 0, dim))
    null = null_bases(jac, pinv, nulls)
    return pinv, null, solutions_curvatures(hessian, null, pinv, across)


@kernel
def minimum_norm_steps(pinv: np.ndarray, res: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """
    Return the Newton steps -J^+ res (K, planned) for residuals res (K, rows).

    Each step is shortened to at most its ``radius`` (K,; inf: as it is).
    """
    count, dim, rows = pinv.shape
    out = np.empty((count, dim))
    for k in range(count):
        size = 0.0
        for i in range(dim):
            total = 0.0
            for r in range(rows):
                total += pinv[k, i, r] * res[k, r]
            out[k, i] = -total
            size += total * total
        shrink = min(1.0, radius[k] / max(np.sqrt(size), 1e-300))
        if shrink < 1.0:
            for i in range(dim):
                out[k, i] *= shrink
    return out


@kernel
def parabola_roots(qa: float, qb: float, qc: float) -> tuple[float, float]:
    """
    Return the real roots of qa z^2 + qb z + qc = 0, stably; NaN, inf where there are none.

    One root (the other NaN) where qa is negligible beside qb.
    """
    if abs(qa) <= 1e-14 * (abs(qb) + 1e-300):
        return np.divide(-qc, qb), np.nan
    q = -0.5 * (qb + np.copysign(np.sqrt(qb * qb - 4.0 * qa * qc), qb))
    return q / qa, np.divide(qc, q)


@kernel
def line_minimax(b: np.ndarray, n: np.ndarray, a: np.ndarray, zlo: float, zhi: float,
                 tie: float) -> float:
    """
    Return the z in [zlo, zhi] that minimises max_i |b_i + n_i z + a_i z^2|.

    Every candidate point is tried: where two |parabolas| are equal (q_i - q_j or q_i + q_j is
    zero), the zeros and stationary points of each, the least total travel (sum_i |q_i| with
    the signs at z = 0), the bounds and 0. Ties (within ``tie``) go to the least total travel,
    then to the first candidate. b, n, a: (m,).
    """
    m = b.shape[0]
    pairs = m * (m - 1) // 2
    quadratics = 2 * pairs + m
    cand = np.empty(2 * quadratics + m + 4)
    # the quadratics in the order: q_i - q_j, q_i + q_j (pairs i < j), q_i; first roots first
    at = 0
    for plus in range(2):
        sign = 1.0 if plus else -1.0
        for i in range(m):
            for j in range(i + 1, m):
                first, second = parabola_roots(a[i] + sign * a[j], n[i] + sign * n[j],
                                               b[i] + sign * b[j])
                cand[at], cand[quadratics + at] = first, second
                at += 1
    for i in range(m):
        cand[at], cand[quadratics + at] = parabola_roots(a[i], n[i], b[i])
        at += 1
    at = 2 * quadratics
    slope, bend = 0.0, 0.0
    for i in range(m):
        cand[at + i] = np.divide(-n[i], 2.0 * a[i])         # stationary points
        side = np.sign(b[i]) if b[i] != 0.0 else np.sign(n[i])
        slope += side * n[i]
        bend += side * a[i]
    at += m
    cand[at] = np.divide(-slope, 2.0 * bend)                # least total travel
    cand[at + 1], cand[at + 2], cand[at + 3] = zlo, zhi, 0.0
    worst = np.empty(cand.shape[0])
    total = np.empty(cand.shape[0])
    least = np.inf
    for s in range(cand.shape[0]):
        z = cand[s] if np.isfinite(cand[s]) else 0.0
        z = min(max(z, zlo), zhi)
        cand[s] = z
        high, sum_ = 0.0, 0.0
        for i in range(m):
            d = abs(b[i] + (n[i] + a[i] * z) * z)
            high = max(high, d)
            sum_ += d
        worst[s], total[s] = high, sum_
        least = min(least, high)
    pick, pick_total = 0, np.inf
    for s in range(cand.shape[0]):
        if worst[s] <= least + tie and total[s] < pick_total:
            pick, pick_total = s, total[s]
    return cand[pick]


@kernel
def line_searches(null: np.ndarray, quad: np.ndarray, base: np.ndarray, start: np.ndarray,
                  scale: np.ndarray, lo: np.ndarray, hi: np.ndarray, radius: np.ndarray,
                  tie: float) -> np.ndarray:
    """
    Return ``base`` (K, m) moved by ``line_minimax`` along each null direction in turn.

    Along direction n (``null`` (K, k, m)) with half the curvature a (the diagonal of ``quad``)
    the joints move by (n + a z) z; the step z keeps the linear part within [lo, hi] and |z|
    within ``radius`` (K,), and minimises the largest scaled displacement from ``start``
    (``scale`` (K, m): ``time_law.tie_scales``), ties within ``tie`` going to the least total
    travel.
    """
    count, nulls, m = null.shape
    out = base.copy()
    b = np.empty(m)
    n = np.empty(m)
    a = np.empty(m)
    for k in range(count):
        x = out[k]
        for j in range(nulls):
            zlo, zhi = -radius[k], radius[k]
            for i in range(m):
                step = null[k, j, i]
                if abs(step) > 1e-15:           # the joint limits along z
                    to_lo, to_hi = (lo[i] - x[i]) / step, (hi[i] - x[i]) / step
                    zlo = max(zlo, min(to_lo, to_hi))
                    zhi = min(zhi, max(to_lo, to_hi))
            zhi = max(zhi, zlo)
            for i in range(m):
                b[i] = (x[i] - start[i]) * scale[k, i]
                n[i] = null[k, j, i] * scale[k, i]
                a[i] = quad[k, j, j, i] * scale[k, i]
            z = line_minimax(b, n, a, zlo, zhi, tie)
            for i in range(m):
                x[i] = x[i] + (null[k, j, i] + quad[k, j, j, i] * z) * z
    return out
