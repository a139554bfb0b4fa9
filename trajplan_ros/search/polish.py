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
form where they are small (up to 3x3), compiled (``active_set``); the best on the model wins.
Near a minimum that is Newton's method on the right active set: it converges in a few steps
where a coordinate descent along the null directions stalls on the ridge where joints tie.
Ties are then broken only by the merit's travel term and by ``iepso._fastest`` among the
candidates. Each step is one compiled kernel (``polish_step``): the trial points, their
linearisation and the trust region's bookkeeping.

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

from trajplan_ros.kinematics.forward import chain_hessian, tool_rows
from trajplan_ros.kinematics.jit import inlined_kernel, kernel
from trajplan_ros.motion.time_law import tie_scales
from trajplan_ros.search.active_set import minimax_step
from trajplan_ros.search.linearisation import (line_searches, linearise, minimum_norm_steps,
                                               residuals_and_jacobians)
from trajplan_ros.search.objective import errors_eq11, Objective, Problem

__all__ = ['EarlyStop', 'Linearisation', 'NEVER', 'agreeing', 'early_stop', 'linearise_at',
           'polish', 'polish_step', 'settle', 'trial_points']

TIE = 1e-12
#: The active sets of the SQP step tie the largest displacement with others among the
#: k + LARGEST largest, and include any of the k nearest limits (a vertex has k + 1
#: pieces, at least one a joint's displacement: up to k can be limits; with two limits only,
#: the Panda missed optima with one joint at the motion time and three on a limit).
LARGEST = 2
#: On sets of 2+ dimensions: chord steps of the second-order correction, and the rejections
#: in a row after which a candidate with an error (m) at most CONVERGED_ERROR counts as
#: converged and leaves the batch.
CHORD_STEPS = 3
STALLED = 5
CONVERGED_ERROR = 1e-9
#: Trust radius (rad) below which a candidate has converged: the motion time it could still
#: gain is of the order of this radius over omega.
SMALLEST_RADIUS = 1e-9
#: Weight of the total joint travel (rad) in the merit, beside omega R (rad): it decides only
#: between steps that leave the motion time as it is (ties, see ``polish``).
TRAVEL_WEIGHT = 1e-6


class _ActiveSets(NamedTuple):
    """The active sets that ``trial_points``'s SQP step tries (``_active_sets``)."""

    pieces: np.ndarray      # (C, k + 1): the pieces of each set
    vertex: np.ndarray      # (C,): the sets of k + 1 pieces, with no unused slot
    clashes: np.ndarray     # (r k, C): 1 where the set holds joint piece t and limit w, at
    #                         row t k + w (a set that ties a joint it holds at a limit)
    r: int                  # pieces 0..r-1 are joints' displacements (ties), r + k unused


@functools.lru_cache(maxsize=16)
def _active_sets(r: int, k: int, vertex_only: bool = False) -> _ActiveSets:
    """
    Return the active sets that ``trial_points``'s SQP step tries (``_ActiveSets``).

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
    pieces = np.array([s for s in sets if not vertex_only or unused not in s],
                      dtype=np.int64).reshape(-1, k + 1)
    clashes = np.array([[t in s and r + w in s for s in pieces.tolist()]
                        for t in range(r) for w in range(k)], dtype=float)
    clashes = clashes.reshape(r * k, len(pieces))
    return _ActiveSets(pieces, ~(pieces == unused).any(axis=1), clashes, r)


class Linearisation(NamedTuple):
    """
    The constraints c(x) linearised at K candidates x (``linearise_at``, ``at``).

    ``quad`` (K, k, k, planned) holds half the second derivatives of the solution set along
    every pair of null directions (on its diagonal x''/2 = -J^+ c''/2 along each direction n,
    with c'' the exact second derivative of c along n). Without null directions (a Newton step
    is all that is needed) ``null`` and ``quad`` are empty.
    """

    c: np.ndarray           # (K, 3 + h) the constraints: the tool point's and held axis'
    time: np.ndarray        # (K,) the motion time R (eq. 10)
    merit: np.ndarray       # (K,) the polish's merit
    pinv: np.ndarray        # (K, planned, 3 + h) J^+, a pseudo-inverse of c's Jacobian J
    null: np.ndarray        # (K, k, planned) N, a basis of J's null space (k null directions)
    quad: np.ndarray        # (K, k, k, planned) Q
    error: np.ndarray       # (K,) the error of eq. (11)

    @classmethod
    def at(cls, obj: Objective, x: np.ndarray, weight: float,
           newton_only: bool = False) -> Linearisation:
        """Return the linearisation at x (K, planned); ``newton_only``: no null space."""
        nulls = 0 if newton_only else obj.null_directions
        return linearise_at(obj.problem, np.ascontiguousarray(x, dtype=float), float(weight),
                            nulls)

    def newton(self, res: np.ndarray, radius: np.ndarray | None = None) -> np.ndarray:
        """
        Return minimum-norm steps dx (K, planned): J dx = -res (least squares off its range).

        With ``radius`` (K,), each shortened to at most its radius.
        """
        if radius is None:
            radius = np.full(len(self.pinv), np.inf)
        return minimum_norm_steps(self.pinv, np.ascontiguousarray(res, dtype=float),
                                  np.ascontiguousarray(radius, dtype=float))

    def keep(self, other: Linearisation, mask: np.ndarray) -> None:
        """Take other's values where mask is true, into these arrays."""
        for mine, theirs in zip(self, other):
            np.copyto(mine, theirs, where=mask.reshape(mask.shape + (1,) * (mine.ndim - 1)))


class EarlyStop(NamedTuple):
    """
    When a polish may end before its last step (``early_stop``; see ``iepso``).

    Once ``agreement`` candidates agree (``agreeing``, settled: error at most ``settled``) and
    no candidate still converging (its trust radius above ``active``, within ``near`` of the
    goal) could beat their answer: one not yet settled that is faster (or, without ``faster``,
    any one not yet settled), or a settled one within 1 % of their time whose time still went
    down in the last step. ``agreement`` 0: never.
    """

    agreement: int
    near: float
    active: float
    settled: float
    faster: bool


#: A polish that runs all its steps (or until every candidate has converged).
NEVER = EarlyStop(0, 0.0, 0.0, 0.0, True)


@kernel
def agreeing(motion_time: np.ndarray, error: np.ndarray, settled: float) -> tuple[int, float]:
    """
    Count the candidates that agree on the answer, and return that count and their time.

    They have settled on the goal (error at most ``settled``) within 1e-6 of the best such
    motion time (0 and inf when none has settled).
    """
    best = np.inf
    for k in range(motion_time.shape[0]):
        if error[k] <= settled:
            best = min(best, motion_time[k])
    count = 0
    for k in range(motion_time.shape[0]):
        count += error[k] <= settled and motion_time[k] <= best * (1 + 1e-6)
    return count, best


@kernel
def early_stop(stop: EarlyStop, motion_time: np.ndarray, error: np.ndarray, radius: np.ndarray,
               previous: np.ndarray, first: bool) -> bool:
    """
    Return whether the polish may end now (``EarlyStop``); ``previous``: the last step's times.

    ``previous`` is overwritten by ``motion_time``; ``first``: the first step (none before).
    """
    if stop.agreement == 0:
        return False
    agree, best = agreeing(motion_time, error, stop.settled)
    blocked = False
    for k in range(motion_time.shape[0]):
        sliding = (first or motion_time[k] < previous[k] * (1 - 1e-12)) and (
            motion_time[k] < best * 1.01)
        settling = error[k] > stop.settled and (motion_time[k] < best or not stop.faster)
        blocked |= (radius[k] > stop.active and error[k] < stop.near
                    and (settling or sliding))
        previous[k] = motion_time[k]
    return agree >= stop.agreement and not blocked


@kernel
def linearise_at(problem: Problem, x: np.ndarray, weight: float, nulls: int) -> Linearisation:
    """
    Return ``linearise``'s c, R, merit, J^+, N and Q at x (K, planned), and the error (eq. 11).

    ``nulls``: the null directions wanted (0: a Newton step is all that is needed).
    """
    walk = tool_rows(problem.chain, x, True)
    dim, vectors = x.shape[1], problem.chain.tail.shape[0]
    hessian = (chain_hessian(walk, vectors) if nulls
               else np.empty((0, dim, dim, vectors, 3)))
    c, time, merit, pinv, null, quad = linearise(
        walk, hessian, x, problem.start, problem.law, problem.omega, problem.goal,
        problem.across, TRAVEL_WEIGHT, weight, nulls)
    error = errors_eq11(walk, problem.goal, problem.ray, problem.across.shape[0],
                        problem.reach)
    return Linearisation(c, time, merit, pinv, null, quad, error)


@inlined_kernel
def clip_to_box(problem: Problem, x: np.ndarray) -> None:
    """Clip x (K, planned) to the search box, in place."""
    lower, upper = problem.lower, problem.upper      # once: each field read takes a reference
    for k in range(x.shape[0]):
        for i in range(x.shape[1]):
            x[k, i] = min(max(x[k, i], lower[i]), upper[i])


@inlined_kernel
def trial_points(problem: Problem, x: np.ndarray, c: np.ndarray, pinv: np.ndarray,
                 null: np.ndarray, quad: np.ndarray, radius: np.ndarray, sets: _ActiveSets,
                 wide: bool) -> np.ndarray:
    """
    Return the polish's trial points from candidates x (K, planned) and their linearisation.

    The Newton step to the solutions (within the trust radii), the step along them (the line
    searches, or on sets of 2+ dimensions the SQP step over the active sets ``sets``, clipped
    to the box), the box, then the second-order correction: chord Newton steps with the
    Jacobian at x, each within the trust radius.
    """
    base = x + minimum_norm_steps(pinv, c, radius)
    scale = tie_scales(problem.law, base, problem.start, problem.omega)
    if wide:
        z = minimax_step(base - problem.start, null, quad, scale,
                         problem.lower - base, problem.upper - base, radius, sets.pieces,
                         sets.vertex, sets.clashes, sets.r)
        for k in range(base.shape[0]):
            for a in range(z.shape[1]):
                base[k] += z[k, a] * null[k, a]
                for b in range(z.shape[1]):
                    base[k] += z[k, a] * z[k, b] * quad[k, a, b]
    else:
        base = line_searches(null, quad, base, problem.start, scale, problem.lower,
                             problem.upper, radius, TIE)
    clip_to_box(problem, base)
    for _ in range(CHORD_STEPS if wide else 1):
        res, _ = residuals_and_jacobians(tool_rows(problem.chain, base, False), problem.goal,
                                         problem.across)
        base += minimum_norm_steps(pinv, res, radius)
        clip_to_box(problem, base)
    return base


@kernel
def polish_step(problem: Problem, x: np.ndarray, model: Linearisation, delta: np.ndarray,
                trust: np.ndarray, rejected: np.ndarray, active: np.ndarray, weight: float,
                sets: _ActiveSets, wide: bool) -> None:
    """
    Take one polish step from the ``active`` candidates x (K, planned), in place (``polish``).

    ``model``: the linearisation at x (updated with x); ``delta``: the trust radii (0:
    converged); ``rejected``: the steps rejected in a row; ``sets``: the SQP step's active sets.
    """
    stepping = np.flatnonzero(active)
    c, time, merit, pinv, null, quad, error = model
    radius = delta[stepping]
    trial = trial_points(problem, x[stepping], c[stepping], pinv[stepping], null[stepping],
                         quad[stepping], radius, sets, wide)
    there = linearise_at(problem, trial, weight, null.shape[1])
    for n in range(stepping.shape[0]):
        k = stepping[n]
        moved = 0.0
        for i in range(x.shape[1]):
            moved += (trial[n, i] - x[k, i]) ** 2
        moved = np.sqrt(moved)
        accept = radius[n] > 0.0 and there.merit[n] < merit[k]
        if accept:
            x[k] = trial[n]
            c[k], time[k], merit[k] = there.c[n], there.time[n], there.merit[n]
            pinv[k], null[k], quad[k], error[k] = (there.pinv[n], there.null[n], there.quad[n],
                                                   there.error[n])
        # a rejected step shrinks the radius below its own length: the same trial again
        # would be rejected again
        delta[k] = min(2 * radius[n], trust[k]) if accept else min(radius[n], moved) / 2
        converged = delta[k] <= SMALLEST_RADIUS
        if wide:        # on the solutions and rejected STALLED times in a row: converged
            rejected[k] = 0 if accept else rejected[k] + 1
            converged |= rejected[k] >= STALLED and error[k] <= CONVERGED_ERROR
            active[k] = not converged          # converged candidates leave the batch
        if converged:
            delta[k] = 0.0


def _prune(model: Linearisation, delta: np.ndarray, active: np.ndarray, count: int) -> None:
    """Leave only the ``count`` active candidates of least merit that have not converged."""
    stepping = np.flatnonzero(active)
    moving = np.where(delta[stepping] > 0.0, model.merit[stepping], np.inf)   # converged: done
    out = stepping[np.argsort(moving, kind='stable')[count:]]
    delta[out] = 0.0
    active[out] = False


def polish(obj: Objective, x: np.ndarray, *, max_steps: int = 30,
           trust: float | np.ndarray = 0.5, stop: EarlyStop = NEVER,
           interrupt: Callable[[], object] | None = None,
           prune: tuple[int, int] | None = None, vertex_steps: int = 0) -> np.ndarray:
    """
    Refine candidates x (K, planned) towards reached, least-motion-time joint goals.

    Each step (``polish_step``, compiled) changes the trust radii: halved or less by each
    rejected step, doubled by each accepted one up to ``trust`` (one for all candidates or one
    each), and 0 once converged. A candidate has converged when its radius falls to
    ``SMALLEST_RADIUS``; on sets of 2+ dimensions also when it is on the solutions and its
    steps were rejected ``STALLED`` times in a row (it then takes no more steps). After every
    step the polish ends when every candidate has converged, when ``stop`` says so
    (``early_stop``) or when ``interrupt`` returns anything but None. ``prune`` = (steps,
    count): after that many steps only the ``count`` candidates of least merit that have not
    converged take more steps; the others are returned where they are. On sets of 2+
    dimensions the first ``vertex_steps`` SQP steps try only the vertex sets of the active
    sets (far from a minimum, the step that counts).
    """
    x = np.clip(np.array(x, dtype=float, ndmin=2), obj.lower, obj.upper)
    k, dim = x.shape
    weight = 1e3 / obj.arm.reach    # on |c|: above any Lagrange multiplier here (exact penalty)
    nulls = obj.null_directions
    model = linearise_at(obj.problem, x, weight, nulls)
    wide = nulls > 1                         # a set of solutions of 2 or more dimensions
    trust = np.array(np.broadcast_to(np.asarray(trust, dtype=float), (k,)))   # writable
    delta = trust.copy()                    # the trust radii; 0 once converged
    active = np.ones(k, dtype=bool)         # the candidates that take steps
    rejected = np.zeros(k, dtype=np.int64)
    previous = np.empty(k)
    for step in range(max_steps):
        if prune is not None and step == prune[0] and active.sum() > prune[1]:
            _prune(model, delta, active, prune[1])
        polish_step(obj.problem, x, model, delta, trust, rejected, active, weight,
                    _active_sets(min(dim, nulls + LARGEST), nulls, step < vertex_steps), wide)
        if (not delta.any() or (interrupt is not None and interrupt() is not None)
                or early_stop(stop, model.time, model.error, delta, previous, step == 0)):
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
    error = obj.errors(obj.tool(x))
    near = (error > below) & (error < 1e-2 * obj.arm.reach)
    if not near.any():
        return x
    here = Linearisation.at(obj, x[near], 1.0, newton_only=True)
    for _ in range(steps):
        trial = np.clip(x[near] + here.newton(here.c), obj.lower, obj.upper)
        there = Linearisation.at(obj, trial, 1.0, newton_only=True)
        better = there.error < here.error
        x[np.flatnonzero(near)[better]] = trial[better]
        here.keep(there, better)
    return x
