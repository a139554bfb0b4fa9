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
form where they are small (up to 3x3), compiled (``active_set``); the best on the model wins
(``_active_set_minimax``). Near a
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
from trajplan_ros.planning.active_set import minimax_step
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


def _active_set_minimax(b: np.ndarray, null: np.ndarray, quad: np.ndarray, scale: np.ndarray,
                        gap_lo: np.ndarray, gap_hi: np.ndarray, limit: np.ndarray,
                        vertex_only: bool = False) -> np.ndarray:
    """
    Return z (K, k) that minimises max_i scale_i |d_i(z)| on the quadratic model of the solutions.

    d(z) = b + z N + z^T Q z (b (K, m): displacements; ``null`` (K, k, m): N, orthonormal rows;
    ``quad`` (K, k, k, m): Q, half the second derivative of the solutions; ``scale`` (m,)).
    The steps keep the joints within [gap_lo, gap_hi] and ||z|| within ``limit`` (K,). The SQP
    step of each active set (``_active_sets`` of the k + _LARGEST largest displacements) is
    judged on the model, compiled (``active_set.minimax_step``); ``vertex_only``: the vertices
    alone (cheaper).
    """
    k, m = null.shape[1:]
    r = min(m, k + _LARGEST)
    sets = _active_sets(r, k, vertex_only)
    arrays = [np.ascontiguousarray(a, dtype=float)
              for a in (b, null, quad, scale, gap_lo, gap_hi, limit)]
    return minimax_step(*arrays, sets.pieces, sets.vertex, sets.clashes, r)


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
