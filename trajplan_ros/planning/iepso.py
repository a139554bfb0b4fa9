"""
IEPSO: PSO with a local-global information-sharing term and last-elimination (section III).

Velocity and position updates, eq. (3)-(5):

    phi3 = C3 R3 |p_g - p_i|
    v <- w v + C1 R1 (p_i - x) + C2 R2 (p_g - x) + phi3
    x <- x + v

with the inertia w falling from 0.9 to 0.4 and C3 from 2 to 0 over ``max_iter`` iterations,
C1 = C2 = 2, R1..R3 uniform in [0, 1] (Table 4). Last-elimination: every ``elimination_period``
iterations the worst ``elimination`` fraction of each swarm (by current F) is replaced by new
particles drawn inside the joint limits.

Additions of ours, documented in the README, each on by default because it measurably helps:

* several independent swarms advance in one array (``swarms``: 16, or 24 in radial mode), so
  the vectorised cost of an iteration barely grows;
* a memetic polish: every ``polish_period`` iterations each swarm's best particle and
  ``polish_count - 1`` random members (5, or 9 in radial mode; for diversity: the polish from a
  random member often lands on a solution branch the swarm has not settled on) are refined by
  ``polish.polish`` (exact reach, least motion time along the solutions, at most
  ``polish_steps`` steps: 8, or 6 in radial mode); the best refined one goes back into its
  swarm, which carries on from there;
* swarm-level last-elimination (``restart``): after a polish round, swarms whose best is worse
  than the overall best by more than ``tol`` are drawn anew;
* the run stops after a polish round when at least ``agreement`` of the refined candidates have
  settled on the goal (error at most ``SETTLED``, 1e-14 m) with the best motion time
  (independent starting points agreeing), or when the best F has improved by less than
  ``tol`` for ``patience_rounds`` rounds (three times as many while the goal is not reached;
  the paper's convergence precision), or after ``max_iter`` iterations. F itself is not
  compared for agreement: eq. (17) changes it by 0.024 per picometre of error, far below any
  meaningful difference;
* a curve search when the run stops on an answer that fewer than ``curve_search`` (15) refined
  candidates agree on: with one free direction (free mode with four planned joints, radial mode
  with five) the solutions through the answer form a curve, cut into arcs by the joint limits,
  and the motion time along it can have several local minima that a local polish cannot see;
  where radial solutions are isolated, the others on the position-only curve through the
  answer are where its axis residual changes sign. ``polish.curve_minima`` follows the curve
  both ways through the limits, the polish refines the seeds it returns, and a faster solution
  replaces the answer. In tuning runs searching after stronger agreement too found nothing
  more, at a higher cost; ``curve_search=0`` turns it off;
* a polish round ends before ``polish_steps`` once that agreement holds and no candidate that is
  still converging (within an eighth of the arm's reach of the goal, its steps still accepted)
  has a shorter motion time: in tuning runs, many fewer polish steps at the same success rate.
"""
from __future__ import annotations

import numpy as np

from trajplan_ros.planning.objective import Objective
from trajplan_ros.planning.optimize import History, OptimizeResult, initial_population
from trajplan_ros.planning.polish import curve_minima, polish as polish_candidates

__all__ = ['iepso', 'FREE_DEFAULTS', 'RADIAL_DEFAULTS']

#: Defaults of ``swarms``, ``polish_count`` and ``polish_steps`` by mode. Radial goals have
#: isolated solutions (as many equations as joints) and the best one is often the landing point
#: of only a few candidates: there more swarms and more polish candidates per swarm find it more
#: often, and six steps are enough for Newton's method to settle on an isolated solution. Free
#: goals have curves of solutions, along which the polish needs its eight steps.
FREE_DEFAULTS = {'swarms': 16, 'polish_count': 6, 'polish_steps': 8}
RADIAL_DEFAULTS = {'swarms': 24, 'polish_count': 10, 'polish_steps': 6}


#: Error (m) below which a refined candidate counts towards agreement. Reaching eps is not
#: enough: eq. (17) rewards the last 5e-10 m with 12 s of F, so a fast candidate still settling
#: at 1e-6 m loses the final choice (least F) to a slower one at 1e-16 m. Below 1e-14 m the
#: reward differs by less than 3e-4 s.
SETTLED = 1e-14


def _agreeing(motion_time: np.ndarray, error: np.ndarray) -> tuple[int, float]:
    """
    How many candidates have settled on the goal (error <= ``SETTLED``) within 1e-6 of the
    best such motion time, and that best time (inf when none has).
    """
    reached = error <= SETTLED
    if not reached.any():
        return 0, np.inf
    best = motion_time[reached].min()
    return int(np.count_nonzero(reached & (motion_time <= best * (1 + 1e-6)))), float(best)


def iepso(obj: Objective, *, population: int = 40, max_iter: int = 1000, tol: float = 1e-7,
          seed: int | np.random.Generator | None = None, swarms: int | None = None, polish: bool = True,
          polish_period: int = 5, polish_count: int | None = None, polish_steps: int | None = None,
          agreement: int = 4, patience_rounds: int = 4, restart: bool = True,
          curve_search: int = 15,
          elimination: float = 0.1, elimination_period: int = 5,
          inertia: tuple[float, float] = (0.9, 0.4), c1: float = 2.0, c2: float = 2.0,
          c3: tuple[float, float] = (2.0, 0.0), max_velocity: float = 0.2) -> OptimizeResult:
    """
    Minimise ``obj`` over the planned joints with IEPSO; see the module docstring.

    ``max_velocity`` caps each velocity component at that fraction of the joint's range.
    ``swarms``, ``polish_count`` and ``polish_steps`` default by mode (``FREE_DEFAULTS``,
    ``RADIAL_DEFAULTS``). Without ``polish`` this is the paper's algorithm alone, stopped by
    ``History.stalled``.
    """
    defaults = RADIAL_DEFAULTS if obj.radial else FREE_DEFAULTS
    swarms = defaults['swarms'] if swarms is None else swarms
    polish_count = defaults['polish_count'] if polish_count is None else polish_count
    polish_steps = defaults['polish_steps'] if polish_steps is None else polish_steps
    if population < 2 or swarms < 1 or max_iter < 1 or polish_count < 1 or polish_period < 1:
        raise ValueError('population must be >= 2; swarms, max_iter, polish_count and '
                         'polish_period >= 1')
    rng = np.random.default_rng(seed)
    lo, hi = obj.lower, obj.upper
    span = hi - lo
    vmax = max_velocity * span
    s, p, dim = swarms, population, lo.size
    n_elim = int(round(elimination * p))
    rows = np.arange(s)

    x = initial_population(rng, lo, hi, (s, p))
    v = (2 * rng.random((s, p, dim)) - 1) * vmax
    ev = obj(x.reshape(-1, dim))
    f = ev.efficiency.reshape(s, p)
    err = ev.error.reshape(s, p)
    nfev = s * p
    pbest, pbest_f, pbest_err = x.copy(), f.copy(), err.copy()
    g_idx = np.argmin(pbest_f, axis=1)
    history = History(max_iter, tol, patience=50, eps=obj.shaping.eps)
    last_polished = np.inf
    stable_rounds = 0
    converged = stop = False

    near = obj.arm.reach / 8

    def enough(r: np.ndarray, error: np.ndarray, active: np.ndarray) -> bool:
        # polish early stop: agreement, and no candidate still converging (near the goal and not
        # stalled) is faster than the agreed one
        agree, best_r = _agreeing(r, error)
        return agree >= agreement and not np.any(active & (error > SETTLED)
                                                 & (error < near) & (r < best_r))

    for it in range(max_iter):
        frac = it / max(max_iter - 1, 1)
        w = inertia[0] + (inertia[1] - inertia[0]) * frac
        k3 = c3[0] + (c3[1] - c3[0]) * frac
        gbest = pbest[rows, g_idx][:, None, :]
        r1, r2, r3 = rng.random((3, s, p, dim))
        v = (w * v + c1 * r1 * (pbest - x) + c2 * r2 * (gbest - x)
             + k3 * r3 * np.abs(gbest - pbest))                        # eq. (3)-(4)
        np.clip(v, -vmax, vmax, out=v)
        x = x + v                                                       # eq. (5)
        outside = (x < lo) | (x > hi)
        x = np.clip(x, lo, hi)
        v[outside] = 0.0
        if n_elim and (it + 1) % elimination_period == 0:               # last-elimination
            worst = np.argsort(f, axis=1)[:, p - n_elim:]
            x[rows[:, None], worst] = initial_population(rng, lo, hi, (s, n_elim))
            v[rows[:, None], worst] = 0.0
        ev = obj(x.reshape(-1, dim))
        f = ev.efficiency.reshape(s, p)
        err = ev.error.reshape(s, p)
        nfev += s * p
        better = f < pbest_f
        pbest = np.where(better[..., None], x, pbest)
        pbest_f = np.where(better, f, pbest_f)
        pbest_err = np.where(better, err, pbest_err)
        g_idx = np.argmin(pbest_f, axis=1)

        if polish and (it + 1) % polish_period == 0:
            # candidates: each swarm's best, and random members for diversity
            top = np.concatenate((g_idx[:, None], rng.integers(0, p, (s, polish_count - 1))), axis=1)
            refined = polish_candidates(obj, pbest[rows[:, None], top].reshape(-1, dim),
                                        max_steps=polish_steps, enough=enough)
            rev = obj(refined)
            rf = rev.efficiency.reshape(s, -1)
            pick = np.argmin(rf, axis=1)
            new_f = rf[rows, pick]
            gain = new_f < pbest_f[rows, g_idx]
            upd = rows[gain]
            slot = g_idx[gain]
            chosen = refined.reshape(s, -1, dim)[rows, pick]
            pbest[upd, slot] = chosen[gain]
            pbest_f[upd, slot] = new_f[gain]
            pbest_err[upd, slot] = rev.error.reshape(s, -1)[rows, pick][gain]
            x[upd, slot] = chosen[gain]
            swarm_best = pbest_f[rows, g_idx]
            best = swarm_best.min()
            best_err = pbest_err[rows, g_idx][np.argmin(swarm_best)]
            # F is hypersensitive to sub-nanometre errors (eq. 17's slope is 12 / s), so agreement
            # is judged on the motion time of the candidates that have settled on the goal
            agree, _ = _agreeing(rev.motion_time, rev.error)
            stable_rounds = stable_rounds + 1 if last_polished - best < tol else 0
            last_polished = best
            reached = best_err <= obj.shaping.eps
            # an unreached goal gets three times the patience before the run gives up
            if (stable_rounds >= patience_rounds * (1 if reached else 3)
                    or (reached and agree >= agreement)):
                converged = reached
                stop = True
                if reached and agree < curve_search:
                    # the polish is local: look for faster arcs along the best answer's curve
                    bs = int(np.argmin(swarm_best))
                    seeds = curve_minima(obj, pbest[bs, g_idx[bs]])
                    if len(seeds):
                        found = polish_candidates(obj, seeds, max_steps=polish_steps)
                        fev = obj(found)
                        i = int(np.argmin(fev.efficiency))
                        if fev.efficiency[i] < best:
                            pbest[bs, g_idx[bs]] = found[i]
                            pbest_f[bs, g_idx[bs]] = fev.efficiency[i]
                            pbest_err[bs, g_idx[bs]] = fev.error[i]
            elif restart and np.any(swarm_best > best + tol):
                # swarm-level last-elimination: swarms stuck above the best start afresh
                lost = rows[swarm_best > best + tol]
                x[lost] = initial_population(rng, lo, hi, (lost.size, p))
                v[lost] = 0.0
                ev = obj(x[lost].reshape(-1, dim))
                nfev += lost.size * p
                pbest[lost] = x[lost]
                pbest_f[lost] = ev.efficiency.reshape(-1, p)
                pbest_err[lost] = ev.error.reshape(-1, p)
                f[lost] = pbest_f[lost]
                g_idx = np.argmin(pbest_f, axis=1)

        flat = int(np.argmin(pbest_f[rows, g_idx]))
        history.record(float(pbest_f[flat, g_idx[flat]]), float(pbest_err[flat, g_idx[flat]]))
        if not polish and history.stalled():
            converged = stop = True
        if stop:
            break

    flat = int(np.argmin(pbest_f[rows, g_idx]))
    return history.result(obj, pbest[flat, g_idx[flat]], nfev, converged)
