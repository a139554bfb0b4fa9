# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
IEPSO: PSO with a local-global information-sharing term and last-elimination (section III).

The paper's algorithm, in its symbols: each particle has a position x (the planned joint
angles), a velocity v and the best position it has visited, p_i; p_g is the best of those in
its swarm. Every iteration, for every particle and joint, eq. (3)-(5):

    phi3 = c3 r3 |p_g - p_i|                                   (3)
    v <- w v + c1 r1 (p_i - x) + c2 r2 (p_g - x) + phi3        (4)
    x <- x + v                                                 (5)

(``fly_eq3_to_5``, compiled; the particles' bests are kept by ``remember_bests``)

with the inertia weight w falling linearly from 0.9 to 0.4 and the acceleration coefficient c3
from 2 to 0 over ``max_iter`` iterations, c1 = c2 = 2, and r1, r2, r3 uniform in [0, 1]
(Table 4). phi3 is the local-global information-sharing term. Last-elimination
(``_last_elimination``): every ``elimination_period`` iterations the worst ``elimination``
fraction of each swarm is replaced by new particles drawn inside the joint limits.

Details the paper leaves open, as we fill them in: r1..r3 are drawn anew for every particle and
joint; the initial velocities are uniform within the velocity cap, each component capped at
``max_velocity`` of its joint's range; a position outside the joint limits is clipped to them
and that velocity component set to 0; last-elimination ranks particles by F at their positions
when last evaluated, and the new particles start at rest; without the polish the run stops by
``History.stalled``, the paper's convergence precision (``tol``).

Additions of ours, documented in the README, each on by default because it measurably helps:

* several independent swarms advance in one array (``swarms``: 8, or 12 in radial mode), so
  the vectorised cost of an iteration barely grows (``_Swarms``);
* a memetic polish (``_polish_round``): every ``polish_period`` iterations each swarm's best
  particle and ``polish_count - 1`` random members (1; for diversity: the polish from a random
  member often lands on a solution branch the swarm has not settled on) are refined by
  ``polish.polish`` (exact reach, least motion time along the solutions, at most
  ``polish_steps`` steps: 6); the best refined one goes back into its swarm, which carries on
  from there. Where the multi-start follows (``_by_multistart``, below) it takes the place of
  the first round: after the first ``polish_period`` iterations it polishes those same
  candidates among its probes, and the run stops if the goal is reached (else polish rounds
  follow as elsewhere, and the multi-start again once they stop);
* swarm-level last-elimination (``restart``, ``_restart``): after a polish round, swarms whose
  best is worse than the overall best by more than ``tol`` are drawn anew;
* the run stops after a polish round (``_Stopping``) when at least ``agreement`` (2) of
  the refined candidates have settled on the goal (error at most ``SETTLED``, 1e-14 m) with
  the best motion time (independent starting points agreeing), or when the best F has
  improved by less than ``tol`` for ``patience_rounds`` rounds (three times as many while the
  goal is not reached; the paper's convergence precision), or after ``max_iter`` iterations.
  F itself is not compared for agreement: eq. (17) changes it by 0.024 per picometre of
  error, far below any meaningful difference;
* a curve search (``_curve_search``) once the run stops, where the solutions form curves
  (one free direction: free mode on four planned joints, radial on six) or lie on them
  (radial mode on four or five: the curves of the position and fewer axis conditions,
  ``curve_constraint``): ``solution_curve`` follows the
  curves through the answer and through ``curve_search`` (20) points drawn inside the limits,
  both ways through the limits, and returns the points where the motion time is least along
  them (on the curves of fewer axis conditions, where the tool axis comes nearest the goal
  ray), where they enter, leave or just touch the limits, and, ten times as finely sampled,
  near the answer.
  The polish refines the seeds that could be faster than the answer (ending early like a
  polish round, below, once one has settled), and the fastest replaces it. This finds the
  optima on a joint limit, at the end of an arc, and on a base or elbow branch that no swarm
  visited, which the swarms and a local polish miss now and then (0.1 % to 0.2 % of goals in
  tuning runs); ``curve_search=0`` turns it off. Elsewhere (``_by_multistart``) a
  multi-start polish from ``WIDE_PROBES`` times as many screened probes, the start and the
  polish round's candidates (``_multistart``) takes its place (isolated solutions in free
  mode, sets of two or more dimensions) and joins it on the longer curves of six planned
  joints;
* the answer (``_answer``) is the fastest p_g on the goal (error at most ``ON_GOAL``, 1e-9 m);
  among equally fast ones (a stretch of solutions along which the slowest joint does not move)
  the one with the least total joint travel sum |x_i - start_i|, which the polish also seeks
  (``polish``); the least F when none is on the goal;
* an ``interrupt`` (the planner's deadline and stop hook), if given, is asked at the end of
  every iteration and after every step of every polish (rounds, curve search, multi-start:
  ``polish``'s ``interrupt``), and its reason ends the run with the best answer so far
  (``OptimizeResult.interrupted``): a stop or a deadline waits at most one polish step, a few
  milliseconds on a 7-joint arm. Asking draws no random numbers, so a run it never ends is
  bit-identical;
* a polish round ends before ``polish_steps`` once that agreement holds and no candidate that is
  still converging (within an eighth of the arm's reach of the goal, its steps still accepted)
  could beat it: one not settled yet that is faster, or a settled one within 1 % that is still
  sliding towards a faster solution (``_polish_is_enough``): in tuning runs, many fewer polish
  steps at the same success rate.

The defaults were tuned on the bench's seeds 0 to 9 and a few other sets of ours; the README's
measured figures use seeds that were not tuned on.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from trajplan_ros.kinematics.jit import kernel
from trajplan_ros.search.goal import Mode
from trajplan_ros.search.objective import Evaluation, Objective
from trajplan_ros.search.optimize import (asked, History, initial_population, Interrupt,
                                          OptimizeResult)
from trajplan_ros.search.polish import agreeing, EarlyStop, polish as polish_candidates, settle
from trajplan_ros.search.solution_curve import curve_constraint, curve_seeds, project_onto_curves

__all__ = ['iepso', 'FREE_DEFAULTS', 'POSE_CURVES_DEFAULTS', 'RADIAL_DEFAULTS']

#: Defaults of ``swarms``, ``polish_count`` and ``polish_steps`` by mode. Radial goals have
#: isolated solutions (as many equations as joints): there more swarms find the best one more
#: often, and six steps are enough for Newton's method to settle on an isolated solution. Free
#: goals have curves of solutions, along which the polish slides for its six steps. The curve
#: search covers the solutions the swarms miss, so one random member per swarm is polished.
FREE_DEFAULTS = {'swarms': 8, 'polish_count': 2, 'polish_steps': 6}
RADIAL_DEFAULTS = {'swarms': 12, 'polish_count': 2, 'polish_steps': 6}
#: A pose whose solutions form curves (seven planned joints): the curves of its several
#: self-motion branches are found by the swarms more than by the curve search; with 12 swarms
#: 97 of 100 Panda goals (seeds 3772, 3782) ended at the fastest, with 24, 99.
POSE_CURVES_DEFAULTS = {'swarms': 24, 'polish_count': 2, 'polish_steps': 6}


#: The multi-start (``_multistart``, ``_by_multistart``): ``WIDE_PROBES`` probes polished per
#: ``curve_search`` point, ``SCREENED`` probes drawn per probe polished, ``SCREEN_ERROR`` the
#: error (in arm reaches) up to which a projected probe counts as on the goal in that
#: screening, ``WIDE_TRUST`` the first polish's trust radius (rad); the ``FINISHED`` fastest
#: polished probes within ``FINISH_NEAR`` (arm reaches) of the goal, on it or still converging,
#: are polished for ``FINISH_STEPS`` more (a probe 1e-3 m off the goal can be the only one in
#: the optimum's basin). ``ROUND_TRUST``: the trust radius (rad) of the swarms' candidates,
#: which join the first polish. ``MULTISTART_PRUNED``: after that many steps of the first
#: polish only that many candidates (of least merit) go on; ``MULTISTART_VERTEX_STEPS``: its
#: first steps try only the vertex sets of the SQP step (``polish``). The measurements behind
#: these values: doc/benchmarks.md, "How the search's settings were chosen".
WIDE_PROBES = 3
#: Where a pose's solutions are isolated (six planned joints), the curve search follows the
#: curves of the tool turning about its axis through ``POSE_CURVE_PROBES`` times
#: ``curve_search`` points, ``POSE_CURVE_STEPS`` steps each way: those curves are long. On 100
#: UR5 goals, 20 walks of 12 steps missed the fastest of its eight solutions on 6, 40 walks of
#: 24 steps on 1 (doc/benchmarks.md, "Full poses").
POSE_CURVE_PROBES = 2
POSE_CURVE_STEPS = 24
SCREENED = 3
SCREEN_ERROR = 1e-6
WIDE_TRUST = 1.5
FINISHED = 4
FINISH_STEPS = 30
FINISH_NEAR = 1e-2
PROJECT_STEPS = 8
MULTISTART_PRUNED = (10, 24)
MULTISTART_VERTEX_STEPS = 3
ROUND_TRUST = 0.5

#: Trust radius (rad) above which a candidate in a polish round still counts as converging
#: (``_polish_is_enough``): a fifth of the polish's, after three rejected steps in a row.
ACTIVE_RADIUS = 0.1

#: Error (m) below which a refined candidate counts towards agreement. Reaching eps is not
#: enough: eq. (17) rewards the last 5e-10 m with 12 s of F, so a fast candidate still settling
#: at 1e-6 m loses the final choice (least F) to a slower one at 1e-16 m. Below 1e-14 m the
#: reward differs by less than 3e-4 s.
SETTLED = 1e-14

#: Error (m) at or below which a candidate counts as on the goal when the answer is chosen
#: (``_fastest``): a thousandth of the default tolerance. Near a singular solution (an elbow
#: almost straight) Newton's method converges only linearly, so a candidate there may stay
#: above ``SETTLED`` for many more steps while its motion time no longer changes.
ON_GOAL = 1e-9


@dataclass
class _Swarms:
    """
    All swarms' particles, as arrays with axes (swarm, particle) or (swarm, particle, joint).

    ``x`` and ``v`` are the positions and velocities, ``f`` F (eq. 9) at the positions as last
    evaluated; ``pbest`` holds each particle's best position p_i, ``pbest_f`` and ``pbest_err``
    its F and error; ``gbest_index`` (swarm,) is the particle whose p_i is its swarm's p_g.
    """

    x: np.ndarray
    v: np.ndarray
    f: np.ndarray
    pbest: np.ndarray
    pbest_f: np.ndarray
    pbest_err: np.ndarray
    gbest_index: np.ndarray
    rows: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.rows = np.arange(self.x.shape[0])

    @property
    def gbest(self) -> np.ndarray:
        """Return each swarm's best position p_g, (swarm, joint)."""
        return self.pbest[self.rows, self.gbest_index]

    @property
    def gbest_f(self) -> np.ndarray:
        """Return F at each swarm's p_g, (swarm,)."""
        return self.pbest_f[self.rows, self.gbest_index]

    def best_swarm(self) -> int:
        """Return the swarm whose p_g has the least F (the first, on a tie)."""
        return int(np.argmin(self.gbest_f))

    def best(self) -> tuple[float, float]:
        """Return F and the error of the best p_g of all swarms."""
        s = self.best_swarm()
        g = self.gbest_index[s]
        return float(self.pbest_f[s, g]), float(self.pbest_err[s, g])

    def replace_gbest(self, swarms: np.ndarray | int, x: np.ndarray, f: np.ndarray | float,
                      error: np.ndarray | float) -> None:
        """Overwrite p_g of ``swarms`` (it stays their best: callers pass only better ones)."""
        g = self.gbest_index[swarms]
        self.pbest[swarms, g] = x
        self.pbest_f[swarms, g] = f
        self.pbest_err[swarms, g] = error


def _linear(bounds: tuple[float, float], frac: float) -> float:
    """Return the value ``frac`` (0 to 1) of the way from ``bounds[0]`` to ``bounds[1]``."""
    return bounds[0] + (bounds[1] - bounds[0]) * frac


def _agreeing(motion_time: np.ndarray, error: np.ndarray, settled: float = SETTLED
              ) -> tuple[int, float]:
    """
    Count the candidates that agree on the answer (``polish.agreeing``).

    They have settled on the goal (error at most ``settled``) within 1e-6 of the best such
    motion time. Return their number and that best time (0 and inf when none has settled).
    """
    return agreeing(motion_time, error, float(settled))


def _polish_is_enough(agreement: int, near: float, active: float = ACTIVE_RADIUS,
                      settled: float = SETTLED, faster: bool = True) -> EarlyStop:
    """
    Build the early stop of one polish (``polish.early_stop``, compiled).

    Stop once ``agreement`` candidates agree (``_agreeing``, settled: error at most
    ``settled``) and no candidate still converging (its trust radius above ``active``, within
    ``near`` of the goal) could beat their answer: one not yet settled that is faster (or,
    without ``faster``, any one not yet settled: off the goal a candidate can be slower on its
    way to a faster solution), or a settled one within 1 % of their time whose time still went
    down in the last step (sliding along the solutions towards a minimum).
    """
    return EarlyStop(int(agreement), float(near), float(active), float(settled), bool(faster))


def _start(obj: Objective, rng: np.random.Generator, swarms: int, population: int,
           vmax: np.ndarray) -> _Swarms:
    """Draw the particles inside the joint limits, velocities within +-vmax, and evaluate."""
    x = initial_population(rng, obj.lower, obj.upper, (swarms, population))
    v = (2 * rng.random(x.shape) - 1) * vmax
    ev = obj(x.reshape(-1, x.shape[-1]))
    f = ev.efficiency.reshape(swarms, population)
    err = ev.error.reshape(swarms, population)
    return _Swarms(x=x, v=v, f=f, pbest=x.copy(), pbest_f=f.copy(), pbest_err=err.copy(),
                   gbest_index=np.argmin(f, axis=1))


@kernel
def fly_eq3_to_5(x: np.ndarray, v: np.ndarray, pbest: np.ndarray, gbest_index: np.ndarray,
                 r: np.ndarray, w: float, c1: float, c2: float, c3: float, vmax: np.ndarray,
                 lower: np.ndarray, upper: np.ndarray) -> None:
    """
    Update the velocities by eq. (3)-(4), each component capped at +-vmax, and move by eq. (5).

    In place, for x, v, pbest (swarm, particle, joint) and each swarm's p_g (``gbest_index``);
    ``w`` and ``c3`` are this iteration's values; r (3, swarm, particle, joint) holds r1, r2,
    r3. A joint that leaves its limits is clipped to them and stops.
    """
    swarms, population, dim = x.shape
    for s in range(swarms):
        g = gbest_index[s]
        for p in range(population):
            for i in range(dim):
                best, gbest = pbest[s, p, i], pbest[s, g, i]
                phi3 = c3 * r[2, s, p, i] * abs(gbest - best)                      # eq. (3)
                speed = (w * v[s, p, i] + c1 * r[0, s, p, i] * (best - x[s, p, i])
                         + c2 * r[1, s, p, i] * (gbest - x[s, p, i]) + phi3)       # eq. (4)
                speed = min(max(speed, -vmax[i]), vmax[i])
                moved = x[s, p, i] + speed                                         # eq. (5)
                if moved < lower[i] or moved > upper[i]:
                    moved, speed = min(max(moved, lower[i]), upper[i]), 0.0
                x[s, p, i], v[s, p, i] = moved, speed


def _fly(swarm: _Swarms, rng: np.random.Generator, w: float, c1: float, c2: float, c3: float,
         vmax: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> None:
    """Move the particles by eq. (3)-(5) (``fly_eq3_to_5``), r1, r2, r3 drawn for each."""
    fly_eq3_to_5(swarm.x, swarm.v, swarm.pbest, swarm.gbest_index,
                 rng.random((3,) + swarm.x.shape), w, c1, c2, c3, vmax, lower, upper)


def _last_elimination(swarm: _Swarms, rng: np.random.Generator, lower: np.ndarray,
                      upper: np.ndarray, count: int) -> None:
    """
    Replace the ``count`` worst particles of each swarm by new ones, at rest.

    Worst by F at their positions when last evaluated; the new positions are uniform within
    the joint limits. The personal bests p_i stay.
    """
    population = swarm.f.shape[1]
    worst = np.argsort(swarm.f, axis=1)[:, population - count:]
    rows = swarm.rows[:, None]
    swarm.x[rows, worst] = initial_population(rng, lower, upper, (rows.size, count))
    swarm.v[rows, worst] = 0.0


@kernel
def remember_bests(x: np.ndarray, f: np.ndarray, error: np.ndarray, pbest: np.ndarray,
                   pbest_f: np.ndarray, pbest_err: np.ndarray, gbest_index: np.ndarray) -> None:
    """
    Keep each particle's best position p_i (by F) and each swarm's best p_g, in place.

    x (swarm, particle, joint), f and error (swarm, particle): the positions just evaluated.
    """
    swarms, population, _ = x.shape
    for s in range(swarms):
        for p in range(population):
            if f[s, p] < pbest_f[s, p]:
                pbest[s, p], pbest_f[s, p], pbest_err[s, p] = x[s, p], f[s, p], error[s, p]
        gbest_index[s] = np.argmin(pbest_f[s])


def _evaluate(swarm: _Swarms, obj: Objective) -> int:
    """Evaluate F at the positions, update p_i and p_g; return the number of evaluations."""
    ev = obj(swarm.x.reshape(-1, swarm.x.shape[-1]))
    swarm.f = ev.efficiency.reshape(swarm.pbest_f.shape)
    remember_bests(swarm.x, swarm.f, ev.error.reshape(swarm.pbest_f.shape), swarm.pbest,
                   swarm.pbest_f, swarm.pbest_err, swarm.gbest_index)
    return swarm.f.size


def _round_members(swarm: _Swarms, rng: np.random.Generator, count: int) -> np.ndarray:
    """Return each swarm's p_g and ``count - 1`` random members' p_i, (swarms count, dim)."""
    swarms, population, dim = swarm.x.shape
    members = np.concatenate((swarm.gbest_index[:, None],
                              rng.integers(0, population, (swarms, count - 1))), axis=1)
    return swarm.pbest[swarm.rows[:, None], members].reshape(-1, dim)


def _polish_round(swarm: _Swarms, obj: Objective, rng: np.random.Generator, count: int,
                  steps: int, stop: EarlyStop, interrupt: Interrupt | None) -> Evaluation:
    """
    Polish each swarm's p_g and ``count - 1`` random members' p_i (ours).

    The best refined candidate of each swarm replaces its p_g, and that particle's position,
    where it is better. Return the evaluation of all refined candidates.
    """
    swarms, _, dim = swarm.x.shape
    refined = polish_candidates(obj, _round_members(swarm, rng, count), max_steps=steps,
                                trust=ROUND_TRUST, stop=stop, interrupt=interrupt)
    ev = obj(refined)
    refined_f = ev.efficiency.reshape(swarms, -1)
    pick = np.argmin(refined_f, axis=1)
    new_f = refined_f[swarm.rows, pick]
    gain = new_f < swarm.gbest_f
    chosen = refined.reshape(swarms, -1, dim)[swarm.rows, pick][gain]
    swarm.x[swarm.rows[gain], swarm.gbest_index[gain]] = chosen
    swarm.replace_gbest(swarm.rows[gain], chosen, new_f[gain],
                        ev.error.reshape(swarms, -1)[swarm.rows, pick][gain])
    return ev


def _round(swarm: _Swarms, obj: Objective, rng: np.random.Generator, stopping: _Stopping,
           count: int, steps: int, interrupt: Interrupt | None) -> tuple[bool, bool]:
    """Run a polish round and ask the stopping rule; return (stop, goal reached) (ours)."""
    refined = _polish_round(swarm, obj, rng, count, steps,
                            _polish_is_enough(stopping.agreement, obj.arm.reach / 8), interrupt)
    # F is hypersensitive to sub-nanometre errors (eq. 17's slope is 12 / s), so agreement is
    # judged on the motion time of the candidates settled on the goal
    agree, _ = _agreeing(refined.motion_time, refined.error)
    return stopping.after_round(*swarm.best(), agree)


def _curve_search(swarm: _Swarms, obj: Objective, rng: np.random.Generator, probes: int,
                  steps: int, count: int, interrupt: Interrupt | None) -> None:
    """
    Polish the seeds along the solution curves (``solution_curve``); keep a better one (ours).

    The curves are those through the answer so far and through ``probes`` points drawn inside
    the limits. A polished seed that ``_fastest`` prefers to the answer (or, while the goal is
    not reached, one with a lower F) replaces the best swarm's p_g (``_keep_fastest``). The
    seeds get four times the polish steps of a round (they may start a little off the
    solutions and far along them from their minimum, and near a straight elbow the polish
    converges only linearly), end early
    once one has settled on the goal and no candidate still converging could beat it
    (``_polish_is_enough``), and are settled by plain Newton steps (``polish.settle``,
    ``_along_curves``). Where ``_by_multistart``, ``_multistart`` polishes ``WIDE_PROBES``
    times ``probes`` screened probes and a polish round's candidates (each swarm's p_g and
    ``count - 1`` random members' p_i), instead of the seeds where the solutions form no
    curves, before them on curves of six planned joints (so that the curves run through its
    answer). ``interrupt``, when it asks to stop, ends every polish at its next step and skips
    what would follow.
    """
    if _isolated_pose(obj):
        probes *= POSE_CURVE_PROBES
    if _by_multistart(obj):
        members = _round_members(swarm, rng, count)
        probed = _probes(obj, rng, probes * WIDE_PROBES)
        _keep_fastest(swarm, obj, _multistart(obj, members, probed, 2 * steps, interrupt))
    if curve_constraint(obj) is not None and asked(interrupt) is None:
        best = _answer(swarm, obj)
        here = obj(best[None, :])
        _keep_fastest(swarm, obj, _along_curves(obj, rng, best, bool(here.error[0] <= ON_GOAL),
                                                probes, steps, interrupt), best, here)


def _keep_fastest(swarm: _Swarms, obj: Objective, polished: np.ndarray,
                  best: np.ndarray | None = None, here: Evaluation | None = None) -> None:
    """
    Put the polished candidate ``_fastest`` prefers to the answer in the best swarm (ours).

    Or, while the answer does not reach the goal, one with a lower F. ``best`` and ``here``:
    the answer and its evaluation, if the caller has them.
    """
    if not len(polished):
        return
    if best is None or here is None:
        best = _answer(swarm, obj)
        here = obj(best[None, :])
    reached = bool(here.error[0] <= ON_GOAL)
    found = np.concatenate((best[None, :], polished))
    ev = obj(polished)
    efficiency = np.concatenate((here.efficiency, ev.efficiency))
    error = np.concatenate((here.error, ev.error))
    i = _fastest(obj, found, error)
    i = int(np.argmin(efficiency)) if i is None else i
    if i > 0 and (reached or efficiency[i] < efficiency[0]):
        swarm.replace_gbest(swarm.best_swarm(), found[i], efficiency[i], error[i])


def _along_curves(obj: Objective, rng: np.random.Generator, best: np.ndarray, reached: bool,
                  probes: int, steps: int, interrupt: Interrupt | None) -> np.ndarray:
    """Return the seeds along the curves through ``best`` and ``probes`` points, polished."""
    points = np.concatenate((best[None, :],
                             initial_population(rng, obj.lower, obj.upper, (probes,))))
    walk = {'steps': POSE_CURVE_STEPS} if _isolated_pose(obj) else {}
    seeds = curve_seeds(obj, points, best if reached else None, **walk)
    if not len(seeds):
        return seeds
    stop = _polish_is_enough(1, obj.arm.reach / 8, active=0.0, settled=ON_GOAL, faster=False)
    return settle(obj, polish_candidates(obj, seeds, max_steps=4 * steps, stop=stop,
                                         interrupt=interrupt),
                  ON_GOAL)


class _Asked:
    """A run's interrupt that remembers the first reason it gave, and then gives only that."""

    def __init__(self, interrupt: Interrupt) -> None:
        self._interrupt = interrupt
        self.reason: str | None = None

    def __call__(self) -> str | None:
        if self.reason is None:
            self.reason = self._interrupt()
        return self.reason


def _cut_by(interrupt: _Asked | None) -> str | None:
    """Return why the interrupt has stopped the run (a polish was cut short), or None."""
    return None if interrupt is None else interrupt.reason


def _by_multistart(obj: Objective) -> bool:
    """
    Return whether ``_multistart`` searches the solutions after the swarm phase (ours).

    A pose: where its solutions form curves (seven planned joints). Isolated pose solutions
    (six) lie on the curves of the tool turning about its axis, which the curve search
    follows.

    Where the curve search does not serve alone: on isolated points in free mode (one to
    three planned joints), where a swarm lands on the fastest less surely than a multi-start
    Newton search from many probes; on sets of two or more dimensions (free mode on five to
    seven, radial on seven), which have no curve to follow; and, beside the curve search, on
    the longer curves of six planned joints (radial mode), where a walk along the curves alone
    can miss a faster stretch. Radial goals on four or five planned joints have isolated
    solutions too, but they lie on the curves of fewer constraints (``curve_constraint``),
    which the curve search follows. Measurements: doc/benchmarks.md, "How the search's
    settings were chosen".
    """
    if obj.mode is Mode.POSE:
        return obj.null_directions >= 1
    if obj.holds_axis:
        return obj.arm.planned >= 6
    return obj.arm.planned != 4


def _isolated_pose(obj: Objective) -> bool:
    """Return whether ``obj`` is a pose whose solutions are isolated points (ours)."""
    return obj.mode is Mode.POSE and obj.null_directions == 0


def _probes(obj: Objective, rng: np.random.Generator, count: int) -> np.ndarray:
    """
    Return ``SCREENED`` times ``count`` probes: half uniform, half around the start (ours).

    Fast joint goals lie near the start, often on a limit: a probe around it is the start plus
    normal noise of a scale drawn log-uniformly from 0.2 to 2 rad per probe, clipped into the
    limits (so some joints sit on them).
    """
    drawn = SCREENED * count
    start = obj.planned_start
    sigma = np.exp(rng.uniform(np.log(0.2), np.log(2.0), (drawn // 2, 1)))
    around = np.clip(start + sigma * rng.standard_normal((drawn // 2, start.size)),
                     obj.lower, obj.upper)
    uniform = initial_population(rng, obj.lower, obj.upper, (drawn - drawn // 2,))
    return np.concatenate((uniform, around))


def _multistart(obj: Objective, bests: np.ndarray, probes: np.ndarray, steps: int,
                interrupt: Interrupt | None) -> np.ndarray:
    """
    Return the swarms' candidates and the best probes polished, the fastest further (ours).

    Where the curve search does not serve (``_by_multistart``). The probes are screened: each
    is projected onto the solutions (``PROJECT_STEPS`` Newton steps), and the ``SCREENED``-th
    part whose projections are fastest on the goal is kept. The swarms' candidates ``bests``
    (with a polish round's trust radius, ``ROUND_TRUST``), the start (the fastest joint goal
    can lie in a narrow basin beside it: a Panda goal at 2.09 s, where the swarms and probes
    found 7.34 s on half the plan seeds) and the kept probes (as drawn: the
    polish from there, with steps as long as ``WIDE_TRUST``, reaches more of the fast minima
    than from the projections) are polished ``steps`` steps (vertex steps first,
    ``MULTISTART_VERTEX_STEPS``; the batch cut near the end, ``MULTISTART_PRUNED``), then the
    ``FINISHED`` fastest near the goal (``FINISH_NEAR``) up to ``FINISH_STEPS`` steps more.
    """
    projected = np.clip(project_onto_curves(obj, probes, PROJECT_STEPS), obj.lower, obj.upper)
    ev = obj(projected)
    keep = np.lexsort((ev.motion_time, ev.error > SCREEN_ERROR * obj.arm.reach))
    start = np.clip(obj.planned_start, obj.lower, obj.upper)
    points = np.concatenate((bests, start[None, :], probes[keep[: len(probes) // SCREENED]]))
    trust = np.where(np.arange(len(points)) < len(bests), ROUND_TRUST, WIDE_TRUST)
    first = polish_candidates(obj, points, max_steps=steps, trust=trust,
                              prune=MULTISTART_PRUNED, vertex_steps=MULTISTART_VERTEX_STEPS,
                              interrupt=interrupt)
    if asked(interrupt) is not None:
        return first
    ev = obj(first)
    order = np.lexsort((ev.motion_time, ev.error > FINISH_NEAR * obj.arm.reach))[:FINISHED]
    stop = _polish_is_enough(1, obj.arm.reach / 8, active=0.0, settled=ON_GOAL)
    finished = polish_candidates(obj, first[order], max_steps=FINISH_STEPS, stop=stop,
                                 interrupt=interrupt)
    return settle(obj, np.concatenate((first, finished)), ON_GOAL)


def _restart(swarm: _Swarms, obj: Objective, rng: np.random.Generator, tol: float) -> int:
    """
    Draw anew, at rest, the swarms whose p_g is worse than the best by more than ``tol`` (ours).

    Swarm-level last-elimination. Return the number of evaluations.
    """
    gbest_f = swarm.gbest_f
    lost = swarm.rows[gbest_f > gbest_f.min() + tol]
    if not lost.size:
        return 0
    population = swarm.x.shape[1]
    swarm.x[lost] = initial_population(rng, obj.lower, obj.upper, (lost.size, population))
    swarm.v[lost] = 0.0
    ev = obj(swarm.x[lost].reshape(-1, swarm.x.shape[-1]))
    swarm.pbest[lost] = swarm.x[lost]
    swarm.pbest_f[lost] = ev.efficiency.reshape(-1, population)
    swarm.pbest_err[lost] = ev.error.reshape(-1, population)
    swarm.f[lost] = swarm.pbest_f[lost]
    swarm.gbest_index = np.argmin(swarm.pbest_f, axis=1)
    return lost.size * population


def _fastest(obj: Objective, x: np.ndarray, error: np.ndarray) -> int | None:
    """
    Return the index of the fastest candidate x (K, planned) on the goal (ours).

    On the goal: error at most ``ON_GOAL``. Among those as fast to 1e-7 (the settled ones, error
    at most ``SETTLED``, if any), the one with the least total joint travel sum |x_i - start_i|.
    None when none is on the goal.
    """
    on_goal = error <= ON_GOAL
    if not on_goal.any():
        return None
    time = np.where(on_goal, obj.motion_time(x), np.inf)
    tied = time <= time.min() * (1 + 1e-7)
    if np.any(tied & (error <= SETTLED)):
        tied &= error <= SETTLED
    travel = np.abs(x - obj.planned_start).sum(axis=1)
    return int(np.argmin(np.where(tied, travel, np.inf)))


def _answer(swarm: _Swarms, obj: Objective) -> np.ndarray:
    """Return the run's answer: the ``_fastest`` p_g, or the least F one when none is on it."""
    i = _fastest(obj, swarm.gbest, swarm.pbest_err[swarm.rows, swarm.gbest_index])
    return swarm.gbest[swarm.best_swarm() if i is None else i]


@dataclass
class _Stopping:
    """
    The stopping rule, asked after each polish round (ours; see the module docstring).

    Stop when ``agreement`` refined candidates agree on a reached goal, or when the best F has
    improved by less than ``tol`` for ``patience_rounds`` rounds (three times as many while the
    goal is not reached, error above ``eps``).
    """

    tol: float
    patience_rounds: int
    agreement: int
    eps: float
    last_best: float = np.inf
    stable_rounds: int = 0

    def after_round(self, best: float, best_err: float, agree: int) -> tuple[bool, bool]:
        """Record the round's best F and its error; return (stop, goal reached)."""
        self.stable_rounds = self.stable_rounds + 1 if self.last_best - best < self.tol else 0
        self.last_best = best
        reached = best_err <= self.eps
        patience = self.patience_rounds * (1 if reached else 3)
        return self.stable_rounds >= patience or (reached and agree >= self.agreement), reached


def _settings(obj: Objective, population: int, max_iter: int, polish_period: int,
              swarms: int | None, polish_count: int | None, polish_steps: int | None,
              agreement: int | None) -> tuple[int, int, int, int]:
    """
    Return ``swarms``, ``polish_count``, ``polish_steps`` and ``agreement``; defaults for None.

    By mode (``FREE_DEFAULTS``, ``RADIAL_DEFAULTS``, ``POSE_CURVES_DEFAULTS``), and
    ``agreement`` 2.
    """
    defaults = (POSE_CURVES_DEFAULTS if obj.mode is Mode.POSE and obj.null_directions >= 1
                else RADIAL_DEFAULTS if obj.holds_axis else FREE_DEFAULTS)
    swarms = defaults['swarms'] if swarms is None else swarms
    polish_count = defaults['polish_count'] if polish_count is None else polish_count
    polish_steps = defaults['polish_steps'] if polish_steps is None else polish_steps
    agreement = 2 if agreement is None else agreement
    if population < 2 or swarms < 1 or max_iter < 1 or polish_count < 1 or polish_period < 1:
        raise ValueError('population must be >= 2; swarms, max_iter, polish_count and '
                         'polish_period >= 1')
    return swarms, polish_count, polish_steps, agreement


def iepso(obj: Objective, *, population: int = 40, max_iter: int = 1000, tol: float = 1e-7,
          seed: int | np.random.Generator | None = None, swarms: int | None = None,
          polish: bool = True, polish_period: int = 5, polish_count: int | None = None,
          polish_steps: int | None = None, agreement: int | None = None,
          patience_rounds: int = 4, restart: bool = True, curve_search: int = 20,
          elimination: float = 0.1, elimination_period: int = 5,
          inertia: tuple[float, float] = (0.9, 0.4),
          c1: float = 2.0, c2: float = 2.0, c3: tuple[float, float] = (2.0, 0.0),
          max_velocity: float = 0.2, interrupt: Interrupt | None = None) -> OptimizeResult:
    """
    Minimise ``obj`` over the planned joints with IEPSO; see the module docstring.

    ``inertia`` and ``c3`` are the (first, last) values of w and c3. ``max_velocity`` caps
    each velocity component at that fraction of the joint's range. ``swarms``,
    ``polish_count`` and ``polish_steps`` default by mode (``..._DEFAULTS``), ``agreement``
    to 2. Without ``polish`` this is the paper's algorithm alone, stopped by
    ``History.stalled``. ``interrupt`` is asked after every iteration and after every polish
    step; its reason ends the run with the best answer so far.
    """
    swarms, polish_count, polish_steps, agreement = _settings(
        obj, population, max_iter, polish_period, swarms, polish_count, polish_steps, agreement)
    rng = np.random.default_rng(seed)
    vmax = max_velocity * (obj.upper - obj.lower)
    eliminated = int(round(elimination * population))
    swarm = _start(obj, rng, swarms, population, vmax)
    nfev = swarm.f.size
    history = History(max_iter, tol, patience=50, eps=obj.shaping.eps)
    stopping = _Stopping(tol, patience_rounds, agreement, obj.shaping.eps)
    stop, converged, interrupted, searched = False, False, None, False
    interrupt = _Asked(interrupt) if interrupt is not None else None
    for it in range(max_iter):
        # the paper's iteration: eq. (3)-(5) and last-elimination, with w and c3 scheduled
        frac = it / max(max_iter - 1, 1)
        _fly(swarm, rng, _linear(inertia, frac), c1, c2, _linear(c3, frac), vmax, obj.lower,
             obj.upper)
        if eliminated and (it + 1) % elimination_period == 0:
            _last_elimination(swarm, rng, obj.lower, obj.upper, eliminated)
        nfev += _evaluate(swarm, obj)
        if polish and (it + 1) % polish_period == 0:        # ours: see the module docstring
            if curve_search and _by_multistart(obj) and not searched:    # in place of a round
                _curve_search(swarm, obj, rng, curve_search, polish_steps, polish_count,
                              interrupt)
                stop = converged = bool(swarm.best()[1] <= obj.shaping.eps)
                searched = True
            else:
                stop, reached = _round(swarm, obj, rng, stopping, polish_count, polish_steps,
                                       interrupt)
                converged = stop and reached
                if stop and curve_search and _cut_by(interrupt) is None:
                    _curve_search(swarm, obj, rng, curve_search, polish_steps, polish_count,
                                  interrupt)
            if not stop and restart and _cut_by(interrupt) is None:
                nfev += _restart(swarm, obj, rng, tol)
        history.record(*swarm.best())
        if not polish and history.stalled():
            converged = stop = True
        # complete when the rule stops, unless a stop cut a polish short on the way
        if (interrupted := _cut_by(interrupt) if stop else asked(interrupt)) or stop:
            break
    return history.result(obj, _answer(swarm, obj), nfev, converged, interrupted)
