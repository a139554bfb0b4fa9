# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The bench's peer for motions around obstacles: OMPL's RRTConnect, then its path simplification.

It plans in the planned joints' space (bounds: the limits), from the start to any of the joint
goals it is given (``GoalStates``: OMPL does no inverse kinematics). A state is valid where the
arm at rest there keeps the padding, a motion between two states where the rest-to-rest direct
motion between them under the plan's time law and timing does, by this package's own
continuous check (``check_motion``, with the start's limits as the planner's detours use). So
the path OMPL returns is free when timed segment by segment with that law, at rest at each
waypoint, and its duration is the sum of the segments'. OMPL 2 (PyPI ``ompl``) is a bench
extra only: it has no rosdep key.
"""
from __future__ import annotations

from dataclasses import dataclass
import time

import numpy as np
from trajplan_ros.collision.distances import CollisionWorld
from trajplan_ros.collision.free_motion import check_motion, StartLimits
from trajplan_ros.motion.motion_profile import Timing
from trajplan_ros.motion.time_law import motion_times, TimeLaw
from trajplan_ros.search.objective import Objective

__all__ = ['PeerPath', 'rrt_connect', 'seed']


@dataclass(frozen=True)
class PeerPath:
    """OMPL's answer: the waypoints (every joint, start and goal included) and its costs."""

    points: tuple[np.ndarray, ...]
    duration: float              # s, the segments' durations summed, at rest at each waypoint
    plan_time: float             # s, planning and simplification


def seed(value: int) -> None:
    """Seed OMPL's random numbers (once a process, before its first plan) and quiet its log."""
    from ompl import util as ou                # the bench extra
    ou.setLogLevel(ou.LOG_ERROR)
    ou.RNG.setSeed(value)


def _vector(state, size: int) -> np.ndarray:
    return np.array([state[i] for i in range(size)])


def rrt_connect(obj: Objective, world: CollisionWorld, law: TimeLaw, timing: Timing,
                goals: np.ndarray, budget: float, simplify: float) -> PeerPath | None:
    """
    Return OMPL's simplified RRTConnect path to one of ``goals`` (planned joints), or None.

    ``budget``: seconds for RRTConnect to find a path; ``simplify``: seconds for
    ``SimpleSetup.simplifySolution``. Deterministic after ``seed`` for the same calls in order.
    """
    from ompl import base as ob, geometric as og      # the bench extra
    size = obj.arm.planned
    limits = StartLimits.at(world, obj.start)

    def free(a: np.ndarray, b: np.ndarray) -> bool:
        return check_motion(world, obj.full(a)[0], obj.full(b)[0], law, timing, False,
                            limits).free

    class DirectMotions(ob.MotionValidator):
        """Valid: the rest-to-rest direct motion between two states keeps the padding."""

        def checkMotion(self, *states) -> bool:                       # noqa: N802 (OMPL's)
            return free(_vector(states[0], size), _vector(states[1], size))

    space = ob.RealVectorStateSpace(size)
    bounds = ob.RealVectorBounds(size)
    for i in range(size):
        bounds.setLow(i, float(obj.lower[i]))
        bounds.setHigh(i, float(obj.upper[i]))
    space.setBounds(bounds)
    info = ob.SpaceInformation(space)
    info.setStateValidityChecker(lambda s: free(_vector(s, size), _vector(s, size)))
    validator = DirectMotions(info)
    info.setMotionValidator(validator)
    info.setup()
    setup = og.SimpleSetup(info)
    start = space.allocState()
    for i in range(size):
        start[i] = float(obj.planned_start[i])
    setup.setStartState(start)
    targets = ob.GoalStates(info)
    for goal in goals:
        state = space.allocState()
        for i in range(size):
            state[i] = float(goal[i])
        targets.addState(state)
    setup.setGoal(targets)
    setup.setPlanner(og.RRTConnect(info))
    clock = time.perf_counter()
    setup.solve(budget)
    if not setup.haveExactSolutionPath():
        return None
    setup.simplifySolution(simplify)
    spent = time.perf_counter() - clock
    path = setup.getSolutionPath()
    points = tuple(obj.full(_vector(path.getState(k), size))[0]
                   for k in range(path.getStateCount()))
    moved = np.abs(np.diff(np.array(points), axis=0))
    duration = float(np.sum(motion_times(law, moved, np.zeros(moved.shape[1]))))
    return PeerPath(points, duration, spent)
