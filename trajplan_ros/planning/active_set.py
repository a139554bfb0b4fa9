# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The polish's SQP step on sets of solutions of k >= 2 dimensions: the minimax over active sets.

Compiled: each candidate tries some hundred active sets, each a few-by-few system, and numpy's
per-call overhead on arrays that small cost several times the arithmetic.

The model (``polish``): the joint displacements along the solutions are d(z) = b + z N +
z^T Q z in the step z (k,), with b the displacements from the start, N (k, m) orthonormal null
directions and Q (k, k, m) half the second derivative of the solutions. The step minimises the
motion time max_i scale_i |d_i(z)| within the joint limits and the trust radius. Each active
set (``polish._active_sets``: joints tying with the largest displacement, each with its sign at
z = 0, and any of the k nearest limits) gives the step of one SQP problem,

    min t   subject to   g_s z - t = -e_s (the set's ties),   n_s z = gap_s (its limits),

in closed form where it is small: a set of k + 1 pieces (a vertex) by its k equations alone, a
smaller one by its KKT system with the Hessian of the Lagrangian. Every step is then judged on
the model and the best one, or z = 0, wins (``minimax_step``).

Small systems are solved by Cramer's rule up to 3x3 and by Gaussian elimination with partial
pivoting beyond. A singular system gives inf or NaN (np.divide: numpy's quotients, where ``/``
would raise), and a step that is not finite is dropped: a vertex set's whole, a KKT set's
component by component (z = 0 there).

The kernels called once per set take no allocation and no branch that ends an array's use
early: numba then holds no reference count on their arrays (a pair of atomic operations per
array and call, which cost more than the arithmetic here).
"""
from __future__ import annotations

import numpy as np

from trajplan_ros.kinematics.jit import kernel

__all__ = ['active_pieces', 'minimax_step', 'sqp_steps']

#: Ridge (on the diagonal) that keeps the small systems regular: the vertex equations, the
#: Hessian of the Lagrangian and the bordered KKT systems' lower right block.
RIDGE = 1e-13
#: Relative ridge on the multipliers' Gram matrix (times its trace, plus 1e-300).
GRAM_RIDGE = 1e-12
#: How far (rad) the linear part of a step may pass a joint limit and still be judged.
SLACK = 1e-12


@kernel
def solve_augmented(m: np.ndarray, n: int) -> bool:
    """
    Solve a x = b in place, m[:n, :n + 1] = [a | b] (x is then m[:n, n]); return: x finite.

    Cramer's rule for n <= 3 (x = sum_s b_s (a_{s+1} x a_{s+2}) / det over the rows a_s for
    n = 3), else Gaussian elimination with partial pivoting.
    """
    if n == 1:
        m[0, 1] = np.divide(m[0, 1], m[0, 0])
    elif n == 2:
        det = m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]
        x0 = np.divide(m[1, 1] * m[0, 2] - m[0, 1] * m[1, 2], det)
        x1 = np.divide(m[0, 0] * m[1, 2] - m[1, 0] * m[0, 2], det)
        m[0, 2], m[1, 2] = x0, x1
    elif n == 3:
        # c_s = a_{s+1} x a_{s+2}
        c00 = m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1]
        c01 = m[1, 2] * m[2, 0] - m[1, 0] * m[2, 2]
        c02 = m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0]
        c10 = m[2, 1] * m[0, 2] - m[2, 2] * m[0, 1]
        c11 = m[2, 2] * m[0, 0] - m[2, 0] * m[0, 2]
        c12 = m[2, 0] * m[0, 1] - m[2, 1] * m[0, 0]
        c20 = m[0, 1] * m[1, 2] - m[0, 2] * m[1, 1]
        c21 = m[0, 2] * m[1, 0] - m[0, 0] * m[1, 2]
        c22 = m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]
        det = m[0, 0] * c00 + m[0, 1] * c01 + m[0, 2] * c02
        b0, b1, b2 = m[0, 3], m[1, 3], m[2, 3]
        m[0, 3] = np.divide(c00 * b0 + c10 * b1 + c20 * b2, det)
        m[1, 3] = np.divide(c01 * b0 + c11 * b1 + c21 * b2, det)
        m[2, 3] = np.divide(c02 * b0 + c12 * b1 + c22 * b2, det)
    else:
        for col in range(n):
            pivot, largest = col, np.abs(m[col, col])
            for row in range(col + 1, n):
                if np.abs(m[row, col]) > largest:
                    pivot, largest = row, np.abs(m[row, col])
            if pivot != col:
                for j in range(col, n + 1):
                    m[col, j], m[pivot, j] = m[pivot, j], m[col, j]
            inverse = np.divide(1.0, m[col, col])
            for row in range(col + 1, n):
                factor = m[row, col] * inverse
                for j in range(col + 1, n + 1):
                    m[row, j] -= factor * m[col, j]
        for row in range(n - 1, -1, -1):
            total = m[row, n]
            for j in range(row + 1, n):
                total -= m[row, j] * m[j, n]
            m[row, n] = np.divide(total, m[row, row])
    finite = True
    for row in range(n):
        finite = finite and np.isfinite(m[row, n])
    return finite


@kernel
def active_pieces(b: np.ndarray, null: np.ndarray, quad: np.ndarray, scale: np.ndarray,
                  gap_lo: np.ndarray, gap_hi: np.ndarray, r: int
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Return the pieces of the active sets per candidate: gradients, Hessians, KKT right sides.

    Pieces: the r largest scaled displacements, each with its sign (g z - t = -e, e its size at
    z = 0), the k nearest limits (n z = the gap to the limit), an unused slot (zeros); ties in
    size or nearness go to the lower joint. Gradients (K, P, k), Hessians (K, P, k, k), right
    sides (K, P), and the joint of each piece (K, P; -1 for the unused slot), with P = r + k + 1
    pieces.
    """
    n_cand, k, m = null.shape
    n_pieces = r + k + 1
    grad, hess = np.zeros((n_cand, n_pieces, k)), np.zeros((n_cand, n_pieces, k, k))
    rhs, joint = np.zeros((n_cand, n_pieces)), np.full((n_cand, n_pieces), -1)
    for i in range(n_cand):
        for p in range(r + k):                  # the r largest, then the k nearest limits
            first = 0 if p < r else r
            best = -1
            for j in range(m):
                taken = False
                for q in range(first, p):
                    taken = taken or joint[i, q] == j
                if taken:
                    continue
                if best < 0:
                    best = j
                elif p < r:
                    if np.abs(b[i, j]) * scale[j] > np.abs(b[i, best]) * scale[best]:
                        best = j
                elif (min(gap_hi[i, j], -gap_lo[i, j])
                      < min(gap_hi[i, best], -gap_lo[i, best])):
                    best = j
            joint[i, p] = best
        for p in range(r + k):
            j = joint[i, p]
            # each piece's sign: the joint's for a displacement, 1 for a limit
            weight = 1.0
            if p < r:
                weight = scale[j] if b[i, j] >= 0.0 else -scale[j]
                rhs[i, p] = -(np.abs(b[i, j]) * scale[j])
            else:
                rhs[i, p] = gap_hi[i, j] if gap_hi[i, j] < -gap_lo[i, j] else gap_lo[i, j]
            for a in range(k):
                grad[i, p, a] = null[i, a, j] * weight
                for c in range(k):
                    hess[i, p, a, c] = quad[i, a, c, j] * (2.0 * weight)
    return grad, hess, rhs, joint


@kernel
def sqp_steps(grad: np.ndarray, hess: np.ndarray, rhs: np.ndarray, joint: np.ndarray,
              pieces: np.ndarray, vertex: np.ndarray, clashes: np.ndarray,
              r: int) -> np.ndarray:
    """
    Return the SQP step z (K, C, k) of every active set (``minimax_step``).

    The problem: min t subject to the set's pieces g z - t = -e (ties) and n z = gap (limits).
    Its first piece is the largest joint's (a tie), so t = g_0 z + e_0, and what is left is in
    z alone: (g_s - tie_s g_0) z = rhs_s - tie_s rhs_0 for the other pieces s. A set of k + 1
    pieces (a vertex: no unused slot) fixes z by those k equations alone; a smaller one takes
    the Hessian of the Lagrangian into account: min g_0 z + z^T H z / 2 subject to its other
    pieces' rows z = values (at most k - 1), with H = sum_s y_s H_s taken at least-squares
    multipliers (min |sum_s y_s g_s| with the ties' y summing to 1) and a ridge of 1e-13: with
    no row the stationary point of the largest joint's displacement; with k - 1 rows (k <= 3)
    along the line they leave, in closed form; else by the KKT system. A set that ties a joint
    it also holds at a limit has no step (z = 0). Non-finite steps are dropped: a vertex set's
    whole, the others' component by component.

    The pieces come from ``active_pieces``; the sets ``pieces`` (C, k + 1), ``vertex`` (C,)
    and ``clashes`` (r k, C) from ``polish._active_sets``, their unused slots last. All in one
    kernel: a kernel called per set would hold reference counts on its arrays, which cost more
    than its arithmetic.
    """
    n_cand, n_pieces, k = grad.shape
    n_sets, unused = pieces.shape[0], r + k
    steps = np.empty((n_cand, n_sets, k))
    rows = np.empty((n_pieces, k + 1))          # each piece's equation in z alone: [rows | values]
    products = np.empty((n_pieces, n_pieces + 1))   # rows_p . rows_q, then rows_p . g_0
    held = np.empty(r * k, dtype=np.int64)
    m = np.empty((2 * k, 2 * k + 1))            # each small system, augmented: [a | b]
    gram, lagrangian, line = np.empty((k, k)), np.empty((k, k)), np.empty(k)
    kkt = False                                 # any set but vertices: their KKT systems
    for t in range(n_sets):
        kkt = kkt or not vertex[t]
    for i in range(n_cand):
        # rows z = values: zero for piece 0 and for the unused slot
        for p in range(n_pieces):
            tie = 1.0 if p < r else 0.0
            for c in range(k):
                rows[p, c] = grad[i, p, c] - tie * grad[i, 0, c]
            rows[p, k] = rhs[i, p] - tie * rhs[i, 0]
        for p in range(n_pieces if kkt else 0):
            for q in range(n_pieces):
                total = 0.0
                for c in range(k):
                    total += rows[p, c] * rows[q, c]
                products[p, q] = total
            total = 0.0
            for c in range(k):
                total += rows[p, c] * grad[i, 0, c]
            products[p, n_pieces] = total
        # the sets that tie a joint they hold at a limit: rows t k + w of clashes
        n_held = 0
        for t in range(r):
            for w in range(k):
                if joint[i, t] == joint[i, r + w]:
                    held[n_held] = t * k + w
                    n_held += 1
        for t in range(n_sets):
            clash = False
            for h in range(n_held):
                clash = clash or clashes[held[h], t] > 0.0
            count = 0                           # the other pieces in use (first in the set)
            for c in range(k):
                count += 1 if pieces[t, 1 + c] != unused else 0
            if clash:
                for c in range(k):
                    steps[i, t, c] = 0.0
                continue
            if vertex[t]:                       # rows z = values, ridged
                for s in range(k):
                    piece = pieces[t, 1 + s]
                    for c in range(k + 1):
                        m[s, c] = rows[piece, c] + (RIDGE if s == c else 0.0)
                finite = solve_augmented(m, k)
                for c in range(k):
                    steps[i, t, c] = m[c, k] if finite else 0.0
                continue
            # the other pieces' multipliers: least |g_0 + rows^T y|, from their Gram matrix
            # with a ridge of 1e-12 its trace + 1e-300 (and 1 on the unused slots' diagonal)
            trace = 0.0
            for s in range(k - 1):
                trace += products[pieces[t, 1 + s], pieces[t, 1 + s]]
            ridge = GRAM_RIDGE * trace + 1e-300
            for s in range(k - 1):
                ps = pieces[t, 1 + s]
                for u in range(k - 1):
                    gram[s, u] = products[ps, pieces[t, 1 + u]]
                gram[s, s] += ridge + (1.0 if ps == unused else 0.0)
                for u in range(k - 1):
                    m[s, u] = gram[s, u]
                m[s, k - 1] = -products[ps, n_pieces]
            solve_augmented(m, k - 1)           # y_1..y_{k-1} in m[:k - 1, k - 1]
            tied = 0.0                          # y_0 = 1 - the other ties' y
            for s in range(k - 1):
                tied += (1.0 if pieces[t, 1 + s] < r else 0.0) * m[s, k - 1]
            for a in range(k):
                for c in range(k):
                    lagrangian[a, c] = 0.0
            for s in range(k):
                weight = 1.0 - tied if s == 0 else m[s - 1, k - 1]
                ps = pieces[t, s]
                for a in range(k):
                    for c in range(k):
                        lagrangian[a, c] += weight * hess[i, ps, a, c]
            for a in range(k):
                lagrangian[a, a] += RIDGE
            if count == k - 1 and k <= 3:
                # the least-norm solution (base) plus s times the line's direction n
                p0, p1 = pieces[t, 1], pieces[t, count]
                if k == 2:
                    line[0], line[1] = -rows[p0, 1], rows[p0, 0]
                else:
                    line[0] = rows[p0, 1] * rows[p1, 2] - rows[p0, 2] * rows[p1, 1]
                    line[1] = rows[p0, 2] * rows[p1, 0] - rows[p0, 0] * rows[p1, 2]
                    line[2] = rows[p0, 0] * rows[p1, 1] - rows[p0, 1] * rows[p1, 0]
                for s in range(count):
                    for u in range(count):
                        m[s, u] = gram[s, u]
                    m[s, count] = rows[pieces[t, 1 + s], k]
                solve_augmented(m, count)
                for a in range(k):              # base
                    total = 0.0
                    for s in range(count):
                        total += rows[pieces[t, 1 + s], a] * m[s, count]
                    steps[i, t, a] = total
                pull, along, curved = 0.0, 0.0, 0.0     # g_0 n, n^T H base, n^T H n
                for a in range(k):
                    pull += grad[i, 0, a] * line[a]
                    hn = 0.0
                    for c in range(k):
                        hn += lagrangian[a, c] * line[c]
                    along += hn * steps[i, t, a]
                    curved += hn * line[a]
                along = np.divide(-(pull + along), curved)
                for a in range(k):
                    z = steps[i, t, a] + along * line[a]
                    steps[i, t, a] = z if np.isfinite(z) else 0.0
                continue
            # H z = -g_0 with no row, else the KKT system
            # [[H, rows^T], [rows, 1e-13 I]] [z; -mu] = [-g_0; values]
            size = k + count
            for a in range(size):
                for c in range(size):
                    m[a, c] = 0.0
            for a in range(k):
                for c in range(k):
                    m[a, c] = lagrangian[a, c]
                m[a, size] = -grad[i, 0, a]
            for s in range(count):
                ps = pieces[t, 1 + s]
                for c in range(k):
                    m[k + s, c] = rows[ps, c]
                    m[c, k + s] = rows[ps, c]
                m[k + s, k + s] = RIDGE
                m[k + s, size] = rows[ps, k]
            solve_augmented(m, size)
            for a in range(k):
                steps[i, t, a] = m[a, size] if np.isfinite(m[a, size]) else 0.0
    return steps


@kernel
def minimax_step(b: np.ndarray, null: np.ndarray, quad: np.ndarray, scale: np.ndarray,
                 gap_lo: np.ndarray, gap_hi: np.ndarray, limit: np.ndarray,
                 pieces: np.ndarray, vertex: np.ndarray, clashes: np.ndarray,
                 r: int) -> np.ndarray:
    """
    Return z (K, k) that minimises max_i scale_i |d_i(z)| on the quadratic model of the solutions.

    d(z) = b + z N + z^T Q z (b (K, m): displacements; ``null`` (K, k, m): N, orthonormal rows;
    ``quad`` (K, k, k, m): Q, half the second derivative of the solutions; ``scale`` (m,)).
    The steps must keep the joints within [gap_lo, gap_hi] and ||z|| within ``limit`` (K,).
    Each active set (``pieces``, ``vertex``, ``clashes``: ``polish._active_sets`` of the r
    largest displacements, ``active_pieces``) gives the SQP step of min t subject to those
    pieces = t (the limits reached), ``sqp_steps``. With k + 1 pieces that is a vertex of the
    linear model, whatever the Hessian. Every step is shortened to the trust radius and judged
    on the model: its linear part z N must keep within the limits, and where the curvature
    term passes a limit the joint is clipped to it, max_i scale_i |b_i + clip((z N +
    z^T Q z)_i)|; the best, or z = 0 (judged first, so it wins ties), wins.
    """
    n_cand, k, m = null.shape
    steps = sqp_steps(*active_pieces(b, null, quad, scale, gap_lo, gap_hi, r), pieces, vertex,
                      clashes, r)
    flat = quad.reshape(n_cand, k * k, m)
    linear, pairs = np.empty(m), np.empty(k * k)
    out = np.zeros((n_cand, k))
    for i in range(n_cand):
        best, usable = 0.0, True                # z = 0: usable where no joint is off limits
        for j in range(m):
            usable = usable and gap_lo[i, j] - SLACK <= 0.0 <= gap_hi[i, j] + SLACK
            best = max(best, np.abs(b[i, j] + min(max(0.0, gap_lo[i, j]), gap_hi[i, j]))
                       * scale[j])
        best, chosen = (best if usable else np.inf), -1
        for t in range(pieces.shape[0]):
            size = 0.0
            for a in range(k):
                size += steps[i, t, a] * steps[i, t, a]
            if size == 0.0:                     # z = 0 again: no better than the first
                continue
            root = np.sqrt(size)                # shortened to the trust radius
            if root > limit[i]:
                shorten = np.divide(limit[i], max(root, 1e-300))
                for a in range(k):
                    steps[i, t, a] *= shorten
            for j in range(m):
                linear[j] = 0.0
            for a in range(k):
                for j in range(m):
                    linear[j] += steps[i, t, a] * null[i, a, j]
            usable = True
            for j in range(m):
                usable = usable and gap_lo[i, j] - SLACK <= linear[j] <= gap_hi[i, j] + SLACK
            if not usable:
                continue
            for a in range(k):
                for c in range(k):
                    pairs[a * k + c] = steps[i, t, a] * steps[i, t, c]
            worst = 0.0
            for j in range(m):
                curve = 0.0                     # z^T Q_j z
                for q in range(k * k):
                    curve += pairs[q] * flat[i, q, j]
                step = min(max(linear[j] + curve, gap_lo[i, j]), gap_hi[i, j])
                worst = max(worst, np.abs(b[i, j] + step) * scale[j])
            if worst < best:
                best, chosen = worst, t
        if chosen >= 0:
            for a in range(k):
                out[i, a] = steps[i, chosen, a]
    return out
