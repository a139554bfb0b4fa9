# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Comparison algorithms of section VI.B on the same objective and budget."""
import itertools

import numpy as np
import pytest

from trajplan_ros.kinematics import paper_arm
from trajplan_ros.planning.planner import ALGORITHMS
from trajplan_ros.search.goal import Goal
from trajplan_ros.search.objective import Objective
from trajplan_ros.tools.bench.cases import PAPER_TARGET as TARGET


@pytest.mark.parametrize('name', ['pso', 'spso', 'ga', 'de'])
def test_baseline_runs_within_budget_and_improves(name):
    obj = Objective(paper_arm(), Goal(TARGET), np.zeros(5))
    res = ALGORITHMS[name](obj, population=40, max_iter=120, seed=7)
    assert res.nfev <= 40 * (120 + 1)
    assert res.nit == res.history_fun.size <= 120
    assert np.all(np.diff(res.history_fun) <= 0)
    assert res.fun == pytest.approx(obj(res.x[None, :]).efficiency[0])
    assert res.history_fun[-1] < res.history_fun[0]
    assert np.all((res.x >= obj.lower) & (res.x <= obj.upper))


@pytest.mark.parametrize('name', ['pso', 'spso', 'ga', 'de'])
def test_baseline_is_deterministic(name):
    obj = Objective(paper_arm(), Goal(TARGET), np.zeros(5))
    a = ALGORITHMS[name](obj, max_iter=30, seed=3)
    b = ALGORITHMS[name](obj, max_iter=30, seed=3)
    assert a.x.tobytes() == b.x.tobytes()


@pytest.mark.parametrize('name', ['pso', 'spso', 'ga', 'de'])
def test_an_interrupt_that_never_fires_changes_nothing(name):
    obj = Objective(paper_arm(), Goal(TARGET), np.zeros(5))
    asked = []
    plain = ALGORITHMS[name](obj, max_iter=200, seed=5)
    watched = ALGORITHMS[name](obj, max_iter=200, seed=5, interrupt=lambda: asked.append(1))
    assert watched.x.tobytes() == plain.x.tobytes() and watched.fun == plain.fun
    assert (watched.nit, watched.nfev, watched.converged) == (plain.nit, plain.nfev,
                                                              plain.converged)
    assert watched.history_fun.tobytes() == plain.history_fun.tobytes()
    assert watched.interrupted is None and len(asked) == plain.nit - plain.converged


@pytest.mark.parametrize('name', ['pso', 'spso', 'ga', 'de'])
def test_an_interrupt_ends_the_run_with_the_best_so_far(name):
    obj = Objective(paper_arm(), Goal(TARGET), np.zeros(5))
    asks = itertools.count()
    res = ALGORITHMS[name](obj, max_iter=200, seed=5,
                           interrupt=lambda: 'stop' if next(asks) >= 9 else None)
    assert res.interrupted == 'stop' and not res.converged
    assert res.nit == res.history_fun.size == 10
    assert res.nfev == 40 * 11
    assert res.fun == pytest.approx(res.history_fun.min(), rel=1e-6)
