# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The comparison algorithms of section VI.B: PSO, SPSO, GA and DE on the same objective.

Each takes the objective, a population size, an iteration cap and a seed, vectorised over the
population, and stops by the same rule as IEPSO without polish (``optimize.History``), so with
the defaults every algorithm has the same budget of population x max_iter evaluations. Like
IEPSO, each asks its ``interrupt`` (if any) after every iteration that the rule has not ended.
The paper does not give their settings; ours are the textbook ones:

* PSO: inertia 0.9 -> 0.4, C1 = C2 = 2, global best (IEPSO without phi3 and elimination).
* SPSO: the "standard PSO" of Bratton and Kennedy (2007): constriction w = 0.7298,
  C1 = C2 = 1.49618, ring topology (each particle sees itself and its two neighbours).
* GA: real-coded, binary tournament selection, blend crossover (BLX-0.5) with rate 0.9,
  Gaussian mutation (10 % of the joint range) with rate 1/dim, one elite.
* DE: DE/rand/1/bin, F = 0.5, CR = 0.9.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from trajplan_ros.search.objective import Objective
from trajplan_ros.search.optimize import (asked, History, initial_population, Interrupt,
                                          OptimizeResult)

__all__ = ['pso', 'spso', 'ga', 'de']

_PATIENCE = 50


class _Run:
    """State shared by the population methods: evaluation, elitist best, history, stopping."""

    def __init__(self, obj: Objective, population: int, max_iter: int, tol: float,
                 seed: int | np.random.Generator | None,
                 interrupt: Interrupt | None = None) -> None:
        if population < 4 or max_iter < 1:
            raise ValueError('population must be >= 4 and max_iter >= 1')
        self.obj, self.rng = obj, np.random.default_rng(seed)
        self.lo, self.hi = obj.lower, obj.upper
        self.history = History(max_iter, tol, _PATIENCE, obj.shaping.eps)
        self.max_iter, self.nfev = max_iter, 0
        self.best_x, self.best_f, self.best_err = None, np.inf, np.inf
        self.interrupt = interrupt
        self.converged, self.interrupted = False, None

    def evaluate(self, x: np.ndarray) -> np.ndarray:
        """Return F for the rows of x, counting them and keeping the best one seen."""
        ev = self.obj(x)
        self.nfev += x.shape[0]
        i = int(np.argmin(ev.efficiency))
        if ev.efficiency[i] < self.best_f:
            self.best_x, self.best_f, self.best_err = x[i].copy(), ev.efficiency[i], ev.error[i]
        return ev.efficiency

    def step_done(self) -> bool:
        """Record the iteration's best; return True when the stopping rule or interrupt ends it."""
        self.history.record(float(self.best_f), float(self.best_err))
        self.converged = self.history.stalled()
        if not self.converged:
            self.interrupted = asked(self.interrupt)
        return self.converged or self.interrupted is not None

    def result(self) -> OptimizeResult:
        """Return the best answer as an ``OptimizeResult``."""
        return self.history.result(self.obj, self.best_x, self.nfev, self.converged,
                                   self.interrupted)


def _swarm(obj: Objective, population: int, max_iter: int, tol: float,
           seed: int | np.random.Generator | None, interrupt: Interrupt | None, *,
           constricted: bool) -> OptimizeResult:
    run = _Run(obj, population, max_iter, tol, seed, interrupt)
    lo, hi = run.lo, run.hi
    vmax = 0.2 * (hi - lo)
    x = initial_population(run.rng, lo, hi, (population,))
    v = (2 * run.rng.random(x.shape) - 1) * vmax
    f = run.evaluate(x)
    pbest, pbest_f = x.copy(), f.copy()
    ring = np.stack((np.roll(np.arange(population), 1), np.arange(population),
                     np.roll(np.arange(population), -1)), axis=1)
    for it in range(max_iter):
        r1, r2 = run.rng.random((2,) + x.shape)
        if constricted:
            w, c1, c2 = 0.7298, 1.49618, 1.49618
            leader = pbest[ring[np.arange(population), np.argmin(pbest_f[ring], axis=1)]]
        else:
            w, c1, c2 = 0.9 - 0.5 * it / max(max_iter - 1, 1), 2.0, 2.0
            leader = pbest[np.argmin(pbest_f)][None, :]
        v = np.clip(w * v + c1 * r1 * (pbest - x) + c2 * r2 * (leader - x), -vmax, vmax)
        x = x + v
        outside = (x < lo) | (x > hi)
        x = np.clip(x, lo, hi)
        v[outside] = 0.0
        f = run.evaluate(x)
        better = f < pbest_f
        pbest[better], pbest_f[better] = x[better], f[better]
        if run.step_done():
            break
    return run.result()


def pso(obj: Objective, *, population: int = 40, max_iter: int = 1000, tol: float = 1e-7,
        seed: int | np.random.Generator | None = None,
        interrupt: Interrupt | None = None) -> OptimizeResult:
    """Run the standard inertia-weight PSO with a global best."""
    return _swarm(obj, population, max_iter, tol, seed, interrupt, constricted=False)


def spso(obj: Objective, *, population: int = 40, max_iter: int = 1000, tol: float = 1e-7,
         seed: int | np.random.Generator | None = None,
         interrupt: Interrupt | None = None) -> OptimizeResult:
    """Run Standard PSO 2007: constriction coefficients and a ring topology."""
    return _swarm(obj, population, max_iter, tol, seed, interrupt, constricted=True)


#: One generation of a population method: (run, x, f) -> (x, f).
_Generation = Callable[[_Run, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


def _generations(obj: Objective, population: int, max_iter: int, tol: float,
                 seed: int | np.random.Generator | None, interrupt: Interrupt | None,
                 generation: _Generation) -> OptimizeResult:
    """Run ``generation(run, x, f) -> (x, f)`` until the stopping rule, interrupt or cap."""
    run = _Run(obj, population, max_iter, tol, seed, interrupt)
    x = initial_population(run.rng, run.lo, run.hi, (population,))
    f = run.evaluate(x)
    for _ in range(max_iter):
        x, f = generation(run, x, f)
        if run.step_done():
            break
    return run.result()


def _ga_generation(run: _Run, x: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rng, lo, hi = run.rng, run.lo, run.hi
    population, dim = x.shape
    pairs = rng.integers(0, population, (2, population))
    parents = x[np.where(f[pairs[0]] < f[pairs[1]], pairs[0], pairs[1])]
    mates = parents[rng.permutation(population)]
    gap = np.abs(parents - mates)
    child = np.minimum(parents, mates) - 0.5 * gap + rng.random(x.shape) * 2.0 * gap
    child = np.where(rng.random((population, 1)) < 0.9, child, parents)
    mutate = rng.random(x.shape) < 1.0 / dim
    child = np.clip(child + mutate * rng.normal(0.0, 0.1, x.shape) * (hi - lo), lo, hi)
    child[0] = run.best_x                                   # elitism
    return child, run.evaluate(child)


def _de_generation(run: _Run, x: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rng = run.rng
    population, dim = x.shape
    idx = np.arange(population)
    # three distinct partners per member, none equal to the member itself
    r = np.argsort(rng.random((population, population - 1)), axis=1)[:, :3]
    r = r + (r >= idx[:, None])
    mutant = x[r[:, 0]] + 0.5 * (x[r[:, 1]] - x[r[:, 2]])
    cross = rng.random(x.shape) < 0.9
    cross[idx, rng.integers(0, dim, population)] = True
    trial = np.clip(np.where(cross, mutant, x), run.lo, run.hi)
    ft = run.evaluate(trial)
    keep = ft < f
    return np.where(keep[:, None], trial, x), np.where(keep, ft, f)


def ga(obj: Objective, *, population: int = 40, max_iter: int = 1000, tol: float = 1e-7,
       seed: int | np.random.Generator | None = None,
       interrupt: Interrupt | None = None) -> OptimizeResult:
    """Run a real-coded GA with tournament selection, BLX-0.5 and Gaussian mutation."""
    return _generations(obj, population, max_iter, tol, seed, interrupt, _ga_generation)


def de(obj: Objective, *, population: int = 40, max_iter: int = 1000, tol: float = 1e-7,
       seed: int | np.random.Generator | None = None,
       interrupt: Interrupt | None = None) -> OptimizeResult:
    """Run differential evolution, DE/rand/1/bin with F = 0.5 and CR = 0.9."""
    return _generations(obj, population, max_iter, tol, seed, interrupt, _de_generation)
