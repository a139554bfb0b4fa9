# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""What every optimiser returns, and the bookkeeping they share (history, stopping rule)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from trajplan_ros.search.objective import Objective

__all__ = ['OptimizeResult', 'History', 'Interrupt', 'asked', 'initial_population']

#: Asked by an optimiser after each iteration (IEPSO also after each polish step): None to carry
#: on, or the reason to end the run now with the best answer so far (the result's
#: ``interrupted``). The optimiser only calls it (no random numbers, no arithmetic), so a run it
#: never ends is bit-identical to a run without it.
Interrupt = Callable[[], str | None]


@dataclass
class OptimizeResult:
    """Best joint goal found by an optimiser (planned joints only), scipy.optimize style."""

    #: Best planned-joint vector (rad).
    x: np.ndarray
    #: Its efficiency scalar F (eq. 9).
    fun: float
    #: Its R (eq. 10), s.
    motion_time: float
    #: Its constraint error (eq. 11), m.
    error: float
    #: Iterations (generations) run.
    nit: int
    #: Objective evaluations used (polish steps not included).
    nfev: int
    #: True when the stopping rule fired before the iteration cap.
    converged: bool
    #: Best F after every iteration.
    history_fun: np.ndarray = field(repr=False)
    #: The error of that best F after every iteration.
    history_error: np.ndarray = field(repr=False)
    #: The interrupt's reason when it ended the run before the stopping rule, else None.
    interrupted: str | None = None


class History:
    """
    Per-iteration record of the best F and its error, and the tolerance-based stopping rule.

    The run has converged when the best F has improved by less than ``tol`` over the last
    ``patience`` iterations while its error is within the reward threshold (the paper's
    "convergence precision").
    """

    def __init__(self, max_iter: int, tol: float, patience: int, eps: float) -> None:
        self.fun = np.empty(max_iter)
        self.error = np.empty(max_iter)
        self.n = 0
        self.tol, self.patience, self.eps = tol, patience, eps

    def record(self, fun: float, error: float) -> None:
        """Append one iteration's best F and its error."""
        self.fun[self.n] = fun
        self.error[self.n] = error
        self.n += 1

    def stalled(self) -> bool:
        """Return True when the stopping rule fires (see the class docstring)."""
        if self.n <= self.patience or self.error[self.n - 1] > self.eps:
            return False
        return self.fun[self.n - 1 - self.patience] - self.fun[self.n - 1] < self.tol

    def result(self, obj: Objective, x: np.ndarray, nfev: int, converged: bool,
               interrupted: str | None = None) -> OptimizeResult:
        """Return the ``OptimizeResult`` for the answer x (planned,), evaluated once more."""
        ev = obj(x[None, :])
        return OptimizeResult(
            x=x.copy(), fun=float(ev.efficiency[0]), motion_time=float(ev.motion_time[0]),
            error=float(ev.error[0]), nit=self.n, nfev=nfev, converged=converged,
            history_fun=self.fun[: self.n].copy(), history_error=self.error[: self.n].copy(),
            interrupted=interrupted)


def asked(interrupt: Interrupt | None) -> str | None:
    """Return the interrupt's reason to end the run now, or None (also without an interrupt)."""
    return None if interrupt is None else interrupt()


def initial_population(rng: np.random.Generator, lower: np.ndarray, upper: np.ndarray,
                       shape: tuple[int, ...]) -> np.ndarray:
    """Return uniform random joint vectors inside the limits, shape ``shape + (dim,)``."""
    return lower + (upper - lower) * rng.random(shape + lower.shape)
