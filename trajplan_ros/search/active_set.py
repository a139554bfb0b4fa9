# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The polish's SQP step on sets of solutions of k >= 2 dimensions: the minimax over active sets.

Compiled: each candidate tries some hundred active sets, each a few-by-few system, and numpy's
per-call overhead on arrays that small cost several times the arithmetic.

The model (``polish``): the joint displacements along the solutions are d(z) = b + z N +
z^T Q z in the step z (k,), with b the displacements from the start, N (k, m) orthonormal null
directions and Q (k, k, m) half the second derivative of the solutions. The step minimises the
motion time max_i scale_i |d_i(z)| (``time_law.tie_scales``, per candidate) within the joint
limits and the trust radius. Each active
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

Each kernel works through every candidate and set, calling only ``solve_augmented`` (one
array) per system: numba holds a reference count, a pair of atomic operations, on each array
a kernel is passed unless its control flow is simple, and per set that cost more than the
arithmetic.
"""
from __future__ import annotations

import numpy as np

from trajplan_ros.kinematics.jit import kernel

__all__ = ['active_pieces', 'best_steps', 'minimax_step', 'solve_augmented', 'sqp_steps']

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
                    if np.abs(b[i, j]) * scale[i, j] > np.abs(b[i, best]) * scale[i, best]:
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
                weight = scale[i, j] if b[i, j] >= 0.0 else -scale[i, j]
                rhs[i, p] = -(np.abs(b[i, j]) * scale[i, j])
            else:
                rhs[i, p] = gap_hi[i, j] if gap_hi[i, j] < -gap_lo[i, j] else gap_lo[i, j]
            for a in range(k):
                grad[i, p, a] = null[i, a, j] * weight
                for c in range(k):
                    hess[i, p, a, c] = quad[i, a, c, j] * (2.0 * weight)
    return grad, hess, rhs, joint


@kernel
def piece_equations(grad: np.ndarray, rhs: np.ndarray, r: int,
                    products: bool) -> tuple[np.ndarray, np.ndarray]:
    """
    Return each piece's equation in z alone, and (with ``products``) their dot products.

    Piece 0 is the largest joint's (a tie), so t = g_0 z + e_0, and what is left of the set's
    pieces is (g_s - tie_s g_0) z = rhs_s - tie_s rhs_0: ``rows`` (K, P, k + 1) = [rows |
    values], zero for piece 0 and for the unused slot. ``dots`` (K, P, P + 1): rows_p .
    rows_q, and in its last column rows_p . g_0 (what the KKT systems need).
    """
    n_cand, n_pieces, k = grad.shape
    rows = np.empty((n_cand, n_pieces, k + 1))
    dots = np.empty((n_cand, n_pieces if products else 0, n_pieces + 1))
    for i in range(n_cand):
        for p in range(n_pieces):
            tie = 1.0 if p < r else 0.0
            for c in range(k):
                rows[i, p, c] = grad[i, p, c] - tie * grad[i, 0, c]
            rows[i, p, k] = rhs[i, p] - tie * rhs[i, 0]
        for p in range(dots.shape[1]):
            for q in range(n_pieces):
                total = 0.0
                for c in range(k):
                    total += rows[i, p, c] * rows[i, q, c]
                dots[i, p, q] = total
            total = 0.0
            for c in range(k):
                total += rows[i, p, c] * grad[i, 0, c]
            dots[i, p, n_pieces] = total
    return rows, dots


@kernel
def clashing(joint: np.ndarray, clashes: np.ndarray, r: int) -> np.ndarray:
    """
    Return (K, C): the sets that tie a joint they also hold at a limit (they take no step).

    ``clashes`` (r k, C): 1 where a set holds joint piece t and limit piece r + w (row t k + w).
    """
    n_cand, n_sets, k = joint.shape[0], clashes.shape[1], clashes.shape[0] // r
    clash = np.zeros((n_cand, n_sets), dtype=np.bool_)
    for i in range(n_cand):
        for t in range(r):
            for w in range(k):
                if joint[i, t] == joint[i, r + w]:
                    for s in range(n_sets):
                        clash[i, s] = clash[i, s] or clashes[t * k + w, s] > 0.0
    return clash


@kernel
def vertex_steps(rows: np.ndarray, pieces: np.ndarray, skip: np.ndarray,
                 steps: np.ndarray) -> None:
    """
    Set ``steps`` (K, C, k) of the vertex sets but ``skip`` (K, C): their other pieces' rows.

    A vertex (k + 1 pieces, no unused slot) fixes z by its k equations rows z = values alone
    (ridged), whatever the Hessian; a step that is not finite is dropped whole (z = 0).
    """
    n_cand, n_sets, k = steps.shape
    m = np.empty((k, k + 1))
    for i in range(n_cand):
        for t in range(n_sets):
            if skip[i, t]:
                continue
            for s in range(k):
                piece = pieces[t, 1 + s]
                for c in range(k + 1):
                    m[s, c] = rows[i, piece, c] + (RIDGE if s == c else 0.0)
            finite = solve_augmented(m, k)
            for c in range(k):
                steps[i, t, c] = m[c, k] if finite else 0.0


@kernel
def lagrangian_hessians(hess: np.ndarray, dots: np.ndarray, pieces: np.ndarray,
                        skip: np.ndarray, r: int) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the Hessians of the Lagrangian (K, C, k, k) of the sets but ``skip``, and Gram matrices.

    H = sum_s y_s H_s + 1e-13 I, at least-squares multipliers: min |sum_s y_s g_s| with the
    ties' y summing to 1, that is the other pieces' y minimising |g_0 + rows^T y| (by their
    Gram matrix, (K, C, k - 1, k - 1), with a ridge of 1e-12 its trace + 1e-300 and 1 on the
    unused slots' diagonal) and y_0 = 1 - the other ties' y. ``dots``: ``piece_equations``.
    """
    n_cand, n_pieces, k = hess.shape[:3]
    n_sets, unused = pieces.shape[0], r + k
    lagrangian = np.empty((n_cand, n_sets, k, k))          # written where not skipped
    gram = np.empty((n_cand, n_sets, k - 1, k - 1))
    m = np.empty((k, k))
    for i in range(n_cand):
        for t in range(n_sets):
            if skip[i, t]:
                continue
            trace = 0.0
            for s in range(k - 1):
                trace += dots[i, pieces[t, 1 + s], pieces[t, 1 + s]]
            ridge = GRAM_RIDGE * trace + 1e-300
            for s in range(k - 1):
                ps = pieces[t, 1 + s]
                for u in range(k - 1):
                    gram[i, t, s, u] = dots[i, ps, pieces[t, 1 + u]]
                gram[i, t, s, s] += ridge + (1.0 if ps == unused else 0.0)
                for u in range(k - 1):
                    m[s, u] = gram[i, t, s, u]
                m[s, k - 1] = -dots[i, ps, n_pieces]
            solve_augmented(m, k - 1)           # y_1..y_{k-1} in m[:k - 1, k - 1]
            tied = 0.0
            for s in range(k - 1):
                tied += (1.0 if pieces[t, 1 + s] < r else 0.0) * m[s, k - 1]
            for a in range(k):
                for c in range(k):
                    total = 0.0
                    for s in range(k):
                        weight = 1.0 - tied if s == 0 else m[s - 1, k - 1]
                        total += weight * hess[i, pieces[t, s], a, c]
                    lagrangian[i, t, a, c] = total + (RIDGE if a == c else 0.0)
    return lagrangian, gram


@kernel
def line_steps(lagrangian: np.ndarray, gram: np.ndarray, rows: np.ndarray, grad: np.ndarray,
               pieces: np.ndarray, skip: np.ndarray, steps: np.ndarray) -> None:
    """
    Set ``steps`` of the sets of k - 1 rows (k <= 3) but ``skip``: min g_0 z + z^T H z / 2.

    Along the line the rows leave: the least-norm solution (base, by their Gram matrix) plus s
    times the line's direction n (normal to the row, or the rows' cross product), s = -(g_0 n
    + n^T H base) / n^T H n. Non-finite components are set to 0.
    """
    n_cand, n_sets, k = steps.shape
    c = k - 1
    m, line = np.empty((k, k)), np.empty(k)
    for i in range(n_cand):
        for t in range(n_sets):
            if skip[i, t]:
                continue
            p0, p1 = pieces[t, 1], pieces[t, c]
            if k == 2:
                line[0], line[1] = -rows[i, p0, 1], rows[i, p0, 0]
            else:
                line[0] = rows[i, p0, 1] * rows[i, p1, 2] - rows[i, p0, 2] * rows[i, p1, 1]
                line[1] = rows[i, p0, 2] * rows[i, p1, 0] - rows[i, p0, 0] * rows[i, p1, 2]
                line[2] = rows[i, p0, 0] * rows[i, p1, 1] - rows[i, p0, 1] * rows[i, p1, 0]
            for s in range(c):
                for u in range(c):
                    m[s, u] = gram[i, t, s, u]
                m[s, c] = rows[i, pieces[t, 1 + s], k]
            solve_augmented(m, c)
            pull, along, curved = 0.0, 0.0, 0.0     # g_0 n, n^T H base, n^T H n
            for a in range(k):
                base = 0.0
                for s in range(c):
                    base += rows[i, pieces[t, 1 + s], a] * m[s, c]
                steps[i, t, a] = base
            for a in range(k):
                pull += grad[i, 0, a] * line[a]
                hn = 0.0
                for u in range(k):
                    hn += lagrangian[i, t, a, u] * line[u]
                along += hn * steps[i, t, a]
                curved += hn * line[a]
            amount = np.divide(-(pull + along), curved)
            for a in range(k):
                z = steps[i, t, a] + amount * line[a]
                steps[i, t, a] = z if np.isfinite(z) else 0.0


@kernel
def bordered_steps(lagrangian: np.ndarray, rows: np.ndarray, grad: np.ndarray,
                   pieces: np.ndarray, skip: np.ndarray, r: int, steps: np.ndarray) -> None:
    """
    Set ``steps`` of the sets but ``skip`` by their KKT systems: min g_0 z + z^T H z / 2.

    Subject to the set's other pieces' rows z = values (their ``count``, unused slots last):
    [[H, rows^T], [rows, 1e-13 I]] [z; -mu] = [-g_0; values]; with no row, H z = -g_0 (the
    stationary point of the largest joint's displacement). Non-finite components are set to 0.
    """
    n_cand, n_sets, k = steps.shape
    m = np.empty((2 * k, 2 * k + 1))
    for i in range(n_cand):
        for t in range(n_sets):
            if skip[i, t]:
                continue
            count = 0
            for c in range(k - 1):
                count += 1 if pieces[t, 1 + c] != r + k else 0
            size = k + count
            for a in range(size):
                for c in range(size):
                    m[a, c] = lagrangian[i, t, a, c] if a < k and c < k else 0.0
            for a in range(k):
                m[a, size] = -grad[i, 0, a]
            for s in range(count):
                ps = pieces[t, 1 + s]
                for c in range(k):
                    m[k + s, c] = rows[i, ps, c]
                    m[c, k + s] = rows[i, ps, c]
                m[k + s, k + s] = RIDGE
                m[k + s, size] = rows[i, ps, k]
            solve_augmented(m, size)
            for a in range(k):
                steps[i, t, a] = m[a, size] if np.isfinite(m[a, size]) else 0.0


@kernel
def sqp_steps(grad: np.ndarray, hess: np.ndarray, rhs: np.ndarray, joint: np.ndarray,
              pieces: np.ndarray, vertex: np.ndarray, clashes: np.ndarray,
              r: int) -> np.ndarray:
    """
    Return the SQP step z (K, C, k) of every active set (``minimax_step``).

    The problem: min t subject to the set's pieces g z - t = -e (ties) and n z = gap (limits),
    in z alone (``piece_equations``). A set of k + 1 pieces (a vertex: no unused slot) fixes z
    by those k equations alone (``vertex_steps``); a smaller one takes the Hessian of the
    Lagrangian into account (``lagrangian_hessians``): with k - 1 rows (k <= 3) along the
    line they leave, in closed form (``line_steps``), else by the KKT system
    (``bordered_steps``). A set that ties a joint it also holds at a limit has no step (z = 0,
    ``clashing``). The pieces come from ``active_pieces``; the sets ``pieces`` (C, k + 1),
    ``vertex`` (C,) and ``clashes`` (r k, C) from ``polish._active_sets``, unused slots last.

    Each kernel works through every candidate and set, calling only ``solve_augmented``: numba
    holds a reference count (a pair of atomic operations) on each array a kernel is passed
    unless its control flow is simple, and per set that cost more than the arithmetic.
    """
    n_cand, k = grad.shape[0], grad.shape[2]
    kkt = not vertex.all()
    rows, dots = piece_equations(grad, rhs, r, kkt)
    clash = clashing(joint, clashes, r)
    steps = np.zeros((n_cand, pieces.shape[0], k))
    vertex_steps(rows, pieces, clash | ~vertex, steps)
    if kkt:
        lagrangian, gram = lagrangian_hessians(hess, dots, pieces, clash | vertex, r)
        line = np.zeros(pieces.shape[0], dtype=np.bool_)
        for t in range(pieces.shape[0]):
            line[t] = k <= 3 and not vertex[t] and pieces[t, k - 1] != r + k
        line_steps(lagrangian, gram, rows, grad, pieces, clash | ~line, steps)
        bordered_steps(lagrangian, rows, grad, pieces, clash | vertex | line, r, steps)
    return steps


@kernel
def best_steps(steps: np.ndarray, b: np.ndarray, null: np.ndarray, quad: np.ndarray,
               scale: np.ndarray, gap_lo: np.ndarray, gap_hi: np.ndarray,
               limit: np.ndarray) -> np.ndarray:
    """
    Return the best of z = 0 and ``steps`` (K, C, k) on the model, each within the trust radius.

    Its linear part z N must keep within the limits, and where the curvature term passes a
    limit the joint is clipped to it: max_i scale_i |b_i + clip((z N + z^T Q z)_i)|, least
    wins, z = 0 (judged first) on ties. ``steps`` are shortened to ``limit`` in place.
    """
    n_cand, k, m = null.shape
    across, curving = np.empty((m, k)), np.empty((m, k * k))    # N and Q by joint
    pairs = np.empty(k * k)
    out = np.zeros((n_cand, k))
    for i in range(n_cand):
        best, usable = 0.0, True                # z = 0: usable where no joint is off limits
        for j in range(m):
            usable = usable and gap_lo[i, j] - SLACK <= 0.0 <= gap_hi[i, j] + SLACK
            moved = np.abs(b[i, j] + min(max(0.0, gap_lo[i, j]), gap_hi[i, j])) * scale[i, j]
            best = max(best, moved)
            for a in range(k):
                across[j, a] = null[i, a, j]
                for c in range(k):
                    curving[j, a * k + c] = quad[i, a, c, j]
        best, chosen = (best if usable else np.inf), -1
        for t in range(steps.shape[1]):
            size = 0.0
            for a in range(k):
                size += steps[i, t, a] * steps[i, t, a]
            if size == 0.0:                     # z = 0 again: no better than the first
                continue
            if np.sqrt(size) > limit[i]:
                shorten = np.divide(limit[i], max(np.sqrt(size), 1e-300))
                for a in range(k):
                    steps[i, t, a] *= shorten
            for a in range(k):
                for c in range(k):
                    pairs[a * k + c] = steps[i, t, a] * steps[i, t, c]
            worst = 0.0
            for j in range(m):                  # until it is off limits or no better
                linear, curve = 0.0, 0.0        # (z N)_j, (z^T Q z)_j
                for a in range(k):
                    linear += steps[i, t, a] * across[j, a]
                if not gap_lo[i, j] - SLACK <= linear <= gap_hi[i, j] + SLACK:
                    worst = np.inf
                for q in range(k * k):
                    curve += pairs[q] * curving[j, q]
                step = min(max(linear + curve, gap_lo[i, j]), gap_hi[i, j])
                worst = max(worst, np.abs(b[i, j] + step) * scale[i, j])
                if worst >= best:
                    break
            if worst < best:
                best, chosen = worst, t
        for a in range(k if chosen >= 0 else 0):
            out[i, a] = steps[i, chosen, a]
    return out


@kernel
def minimax_step(b: np.ndarray, null: np.ndarray, quad: np.ndarray, scale: np.ndarray,
                 gap_lo: np.ndarray, gap_hi: np.ndarray, limit: np.ndarray,
                 pieces: np.ndarray, vertex: np.ndarray, clashes: np.ndarray,
                 r: int) -> np.ndarray:
    """
    Return z (K, k) that minimises max_i scale_i |d_i(z)| on the quadratic model of the solutions.

    d(z) = b + z N + z^T Q z (b (K, m): displacements; ``null`` (K, k, m): N, orthonormal rows;
    ``quad`` (K, k, k, m): Q, half the second derivative of the solutions; ``scale`` (K, m)).
    The steps must keep the joints within [gap_lo, gap_hi] and ||z|| within ``limit`` (K,).
    Each active set (``pieces``, ``vertex``, ``clashes``: ``polish._active_sets`` of the r
    largest displacements, ``active_pieces``) gives the SQP step of min t subject to those
    pieces = t (the limits reached), ``sqp_steps``. With k + 1 pieces that is a vertex of the
    linear model, whatever the Hessian. Every step is shortened to the trust radius and judged
    on the model; the best, or z = 0, wins (``best_steps``).
    """
    grad, hess, rhs, joint = active_pieces(b, null, quad, scale, gap_lo, gap_hi, r)
    steps = sqp_steps(grad, hess, rhs, joint, pieces, vertex, clashes, r)
    return best_steps(steps, b, null, quad, scale, gap_lo, gap_hi, limit)
