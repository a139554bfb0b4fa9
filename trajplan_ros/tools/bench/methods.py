# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The benchmark's methods: the paper's algorithms through ``plan``, and the peers scipy and pyswarms.

``METHODS`` holds, in table order: the five algorithms of the paper through ``plan`` (IEPSO, PSO,
SPSO, GA, DE), each with the default rewards-and-punishment term and with
``RewardPunishment(reward=False)`` (suffix ``-noreward``, Fig. 10); IEPSO as published
(``iepso-paper``: one swarm of 40, no polish); IEPSO without its curve search
(``iepso-nocurve``, an ablation); and scipy's ``differential_evolution`` (vectorised, polished,
scipy's other defaults) and pyswarms' ``GlobalBestPSO`` (40 particles, 1000 iterations)
minimising the same ``Objective``.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass
from functools import partial
import importlib
import importlib.util
import os
from pathlib import Path
import tempfile
from typing import Callable, Iterator, Mapping, Sequence

import numpy as np

from trajplan_ros.kinematics import ArmModel
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.planning.planner import ALGORITHMS, plan, PlanResult
from trajplan_ros.search.fuzzy import RewardPunishment
from trajplan_ros.search.goal import Goal, Mode
from trajplan_ros.search.objective import Objective, planned_arm

__all__ = ['Answer', 'Method', 'METHODS', 'ITERATIONS', 'PARTICLES', 'PYSWARMS_OPTIONS',
           'load', 'pyswarms_logging']

#: Swarm size and iteration cap of the paper (Table 4), also given to pyswarms.
PARTICLES, ITERATIONS = 40, 1000
#: Constriction coefficients of Clerc and Kennedy (2002) for pyswarms.
PYSWARMS_OPTIONS = {'c1': 1.49618, 'c2': 1.49618, 'w': 0.7298}
_NO_REWARD = RewardPunishment(reward=False)
#: The variable in which every pyswarms ``Reporter`` looks for a logging configuration file.
_PYSWARMS_LOG_CFG = 'LOG_CFG'
#: A ``logging.config.dictConfig`` configuration that changes nothing: incremental, naming no
#: handler and no logger (YAML, as pyswarms reads it).
_UNCHANGED_LOGGING = 'version: 1\nincremental: true\n'


@dataclass(frozen=True)
class Answer:
    """
    A method's joint goal for the planned joints (rad), with the plan when ``plan`` made it.

    ``joints``: every joint's angle, when the method gives them (ikpy). ``seconds``: the time of
    the plan as the method measured it (a baseline in another process), else the call's.
    """

    x: np.ndarray
    plan: PlanResult | None = None
    joints: np.ndarray | None = None
    seconds: float | None = None


#: ``solve(arm, mode, goal, start, seed, profile, orientation=None, tolerances=None)``;
#: ``orientation`` is a pose goal's quaternion (x, y, z, w), ``tolerances`` the plan's
#: ``tolerance``, ``axis_tolerance`` and ``orientation_tolerance`` (those given; the peers,
#: which reach the goal itself, take no tolerance).
Solver = Callable[..., Answer]


@dataclass(frozen=True)
class Method:
    """
    A row of the benchmark: ``solve(arm, mode, goal, start, seed, profile, ...)`` (``Solver``).

    ``requires`` names the optional package the method needs and ``imports`` the module it
    imports when it runs (``load`` imports it before the timed calls).
    """

    name: str
    description: str
    solve: Solver
    requires: str | None = None
    imports: str | None = None

    @property
    def available(self) -> bool:
        """Tell whether the package the method needs is installed."""
        return self.requires is None or importlib.util.find_spec(self.requires) is not None


@contextmanager
def pyswarms_logging() -> Iterator[None]:
    """
    Keep the process's logging as it is while pyswarms imports and builds its objects.

    Every pyswarms ``Reporter`` (several are made when pyswarms is imported, one by each optimiser
    and topology) passes the YAML file named by the environment variable ``LOG_CFG`` to
    ``logging.config.dictConfig``; without one it loads a default that replaces the root logger's
    handlers and opens ./report.log in the working directory. For the duration, ``LOG_CFG`` names
    an incremental configuration of nothing, in a temporary folder; the variable is restored after.
    """
    before = os.environ.get(_PYSWARMS_LOG_CFG)
    with tempfile.TemporaryDirectory(prefix='trajplan-bench-') as folder:
        config = Path(folder) / 'logging.yaml'
        config.write_text(_UNCHANGED_LOGGING, encoding='utf-8')
        os.environ[_PYSWARMS_LOG_CFG] = str(config)
        try:
            yield
        finally:
            if before is None:
                del os.environ[_PYSWARMS_LOG_CFG]
            else:
                os.environ[_PYSWARMS_LOG_CFG] = before


def load(methods: Sequence[Method]) -> None:
    """Import the modules the methods need now, so that no timed call pays for the import."""
    with pyswarms_logging():
        for method in methods:
            if method.imports:
                importlib.import_module(method.imports)


def _core(algorithm: str, shaping: RewardPunishment | None, options: dict | None,
          arm: ArmModel, mode: Mode, goal: np.ndarray, start: np.ndarray, seed: int,
          profile: MotionProfile, orientation: np.ndarray | None = None,
          tolerances: Mapping[str, float] | None = None) -> Answer:
    result = plan(goal, start, arm=arm, mode=mode, algorithm=algorithm, seed=seed,
                  shaping=shaping, optimizer_options=options, motion=profile,
                  orientation=orientation, **(tolerances or {}))
    if result.joint_goal is None:
        raise ValueError(f'{algorithm} rejected goal {goal.tolist()}: {result.message}')
    planned = planned_arm(arm, mode).planned                             # as the objective plans
    return Answer(result.joint_goal[:planned], result)


def _scipy_de(arm: ArmModel, mode: Mode, goal: np.ndarray, start: np.ndarray, seed: int,
              profile: MotionProfile, orientation: np.ndarray | None = None,
              tolerances: Mapping[str, float] | None = None) -> Answer:
    from scipy.optimize import differential_evolution

    obj = Objective(arm, Goal(goal, mode=mode, orientation=orientation), start, profile=profile)
    # vectorized: x is (planned, S) for a generation and (planned, 1) while polishing
    found = differential_evolution(lambda x: obj(x.T).efficiency, list(zip(obj.lower, obj.upper)),
                                   vectorized=True, updating='deferred', polish=True,
                                   rng=np.random.default_rng(seed))
    return Answer(np.asarray(found.x))


def _pyswarms(arm: ArmModel, mode: Mode, goal: np.ndarray, start: np.ndarray, seed: int,
              profile: MotionProfile, orientation: np.ndarray | None = None,
              tolerances: Mapping[str, float] | None = None) -> Answer:
    obj = Objective(arm, Goal(goal, mode=mode, orientation=orientation), start, profile=profile)
    state = np.random.get_state()             # pyswarms draws from numpy's global generator
    np.random.seed(seed)
    try:
        with pyswarms_logging():
            from pyswarms.single import GlobalBestPSO

            swarm = GlobalBestPSO(n_particles=PARTICLES, dimensions=obj.lower.size,
                                  options=PYSWARMS_OPTIONS, bounds=(obj.lower, obj.upper))
        _, x = swarm.optimize(lambda x: obj(x).efficiency, iters=ITERATIONS, verbose=False)
    finally:
        np.random.set_state(state)
    return Answer(np.asarray(x, dtype=float))


def _paper_rows(algorithm: str) -> list[Method]:
    """Return the rows of one of the paper's algorithms run through ``plan``."""
    label = algorithm.upper()
    what = ('this package: several swarms and a memetic polish' if algorithm == 'iepso'
            else "the paper's comparison")
    rows = [Method(algorithm, f'{label} ({what}), rewards and punishment',
                   partial(_core, algorithm, None, None)),
            Method(f'{algorithm}-noreward', f'{label} without the reward (Fig. 10)',
                   partial(_core, algorithm, _NO_REWARD, None))]
    if algorithm == 'iepso':
        paper = {'polish': False, 'swarms': 1}
        rows += [Method('iepso-paper', 'IEPSO as published: one swarm of 40, no polish',
                        partial(_core, algorithm, None, paper)),
                 Method('iepso-paper-noreward', 'IEPSO as published, without the reward',
                        partial(_core, algorithm, _NO_REWARD, paper)),
                 Method('iepso-nocurve', 'IEPSO without the curve search (an ablation)',
                        partial(_core, algorithm, None, {'curve_search': 0}))]
    return rows


def _methods() -> dict[str, Method]:
    rows = [row for algorithm in ALGORITHMS for row in _paper_rows(algorithm)]
    rows.append(Method('scipy-de', 'scipy.optimize.differential_evolution (vectorized, polish)',
                       _scipy_de, 'scipy', 'scipy.optimize'))
    rows.append(Method('pyswarms', f'pyswarms GlobalBestPSO ({PARTICLES} particles, '
                       f'{ITERATIONS} iterations)', _pyswarms, 'pyswarms', 'pyswarms.single'))
    return {m.name: m for m in rows}


#: Every benchmark row by name, in table order.
METHODS: dict[str, Method] = _methods()
