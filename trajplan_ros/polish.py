"""Local polish of candidate joint goals: exact reach, then least motion time along the solutions.

Not part of the paper. The swarm finds the basin; this finishes the job to machine precision.
It is sequential linear programming on

    minimise max_i |x_i - start_i|   subject to   c(x) = 0 (reach, and the axis in radial mode),
                                                   lower <= x <= upper,

vectorised over K candidates. Each step linearises c, takes the minimum-norm Newton correction
-J^+ c, and then moves along the null space of J (the directions that keep the goal reached)
to where the linearised motion time is least. Along one null direction that is a convex
piecewise-linear function of one variable, minimised exactly by checking its breakpoints; ties
(every joint but the slowest has slack) go to the least total joint travel, which makes plans
repeatable. With more than one null direction (arms with more than four planned joints) the
directions are taken in turn, a coordinate descent that may stop short of the optimum.
A trust radius, a second-order correction and the merit R + W |c| make the steps safe.
"""
from __future__ import annotations

import numpy as np

from .objective import Objective

__all__ = ["polish"]

_TIE = 1e-12


def _line_minimax(b: np.ndarray, n: np.ndarray, zlo: np.ndarray, zhi: np.ndarray) -> np.ndarray:
    """argmin over z in [zlo, zhi] of max_i |b_i + n_i z|, ties to least sum_i |b_i + n_i z|.

    b, n: (K, m); zlo, zhi: (K,). Returns z (K,).
    """
    m = b.shape[1]
    iu, ju = np.triu_indices(m, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        cand = np.concatenate((
            -(b[:, iu] - b[:, ju]) / (n[:, iu] - n[:, ju]),
            -(b[:, iu] + b[:, ju]) / (n[:, iu] + n[:, ju]),
            -b / n,
            zlo[:, None], zhi[:, None], np.zeros((b.shape[0], 1)),
        ), axis=1)
    cand = np.where(np.isfinite(cand), cand, 0.0)
    cand = np.clip(cand, zlo[:, None], zhi[:, None])
    d = np.abs(b[:, None, :] + n[:, None, :] * cand[:, :, None])        # (K, C, m)
    worst = d.max(axis=2)
    total = d.sum(axis=2)
    best = worst.min(axis=1, keepdims=True)
    total = np.where(worst <= best + _TIE, total, np.inf)
    return cand[np.arange(b.shape[0]), np.argmin(total, axis=1)]


def _merit(obj: Objective, x: np.ndarray, weight: float) -> tuple[np.ndarray, np.ndarray]:
    """Residuals c(x) and the merit max_i |x_i - start_i| + weight |c(x)|."""
    p, u = obj.arm.tool(obj.full(x))
    c = obj.residuals(p, u)
    return c, obj.motion_time(x) * obj.omega + weight * np.linalg.norm(c, axis=1)


def polish(obj: Objective, x: np.ndarray, *, max_steps: int = 30, trust: float = 0.5) -> np.ndarray:
    """Refine candidates x (K, planned) towards reached, least-motion-time joint goals."""
    lo, hi = obj.lower, obj.upper
    start = obj.start[: obj.arm.planned]
    x = np.clip(np.array(x, dtype=float, ndmin=2), lo, hi)
    k, m = x.shape
    rank = min(obj.n_constraints, m)
    # Penalty on |c| (metres, and the dimensionless axis residual): larger than any Lagrange
    # multiplier of this problem, so that the merit's minimum is the constrained one.
    weight = 1e3 / obj.arm.reach
    _, merit = _merit(obj, x, weight)
    delta = np.full(k, trust)
    live = np.ones(k, dtype=bool)
    for _ in range(max_steps):
        p, u, jp, ju = obj.arm.tool_jacobian(obj.full(x))
        c = obj.residuals(p, u)
        jac = np.concatenate((jp, ju[:, 2:3]), axis=1) if obj.radial else jp
        u_, s_, vt = np.linalg.svd(jac, full_matrices=True)
        s_inv = np.where(s_ > 1e-9 * s_[:, :1], 1.0 / np.where(s_ > 0, s_, 1.0), 0.0)[:, :rank]
        u_r, vt_r = u_[:, :, :rank], vt[:, :rank, :]

        def newton(res: np.ndarray) -> np.ndarray:
            return -np.einsum("kij,ki->kj", vt_r, np.einsum("kri,kr->ki", u_r, res) * s_inv)

        step = newton(c)
        size = np.linalg.norm(step, axis=1)
        step *= np.minimum(1.0, delta / np.maximum(size, 1e-300))[:, None]
        base = x + step
        for j in range(rank, m):
            direction = vt[:, j, :]
            safe = np.where(np.abs(direction) > 1e-15, direction, np.nan)
            a_lo, a_hi = (lo - base) / safe, (hi - base) / safe
            zlo = np.maximum(-delta, np.nanmax(np.fmin(a_lo, a_hi), axis=1, initial=-np.inf))
            zhi = np.maximum(np.minimum(delta, np.nanmin(np.fmax(a_lo, a_hi), axis=1, initial=np.inf)), zlo)
            z = _line_minimax(base - start, direction, zlo, zhi)
            base = base + z[:, None] * direction
        trial = np.clip(base, lo, hi)
        c_trial, _ = _merit(obj, trial, weight)
        trial = np.clip(trial + newton(c_trial), lo, hi)      # second-order correction
        _, m_trial = _merit(obj, trial, weight)
        moved = np.max(np.abs(trial - x), axis=1)
        accept = live & (m_trial < merit)
        x[accept] = trial[accept]
        merit[accept] = m_trial[accept]
        delta = np.where(accept, np.minimum(2 * delta, trust), delta / 2)
        live &= (moved > 1e-13) & (delta > 1e-13)
        if not live.any():
            break
    return x
