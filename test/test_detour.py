# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Motions through via points where no direct motion is free, checked by python-fcl."""
from pathlib import Path

import numpy as np
import pytest
from trajplan_ros import plan, PlanStatus
from trajplan_ros.collision.free_motion import START_TOLERANCE
from trajplan_ros.planning.planner import PlanRequest
from trajplan_ros.tools.bench.clearance import IndependentCheck
from trajplan_ros.tools.bench.collision_bench import (BenchArm, draw_goal, draw_scene,
                                                      every_millisecond)


@pytest.fixture(scope='module')
def blocked(tmp_path_factory: pytest.TempPathFactory):
    """Return the bench's paper arm, a scene and a goal that no direct motion reaches freely."""
    bench = BenchArm.load('paper', Path(tmp_path_factory.mktemp('arm')))
    rng = np.random.default_rng(12)             # bench-collisions' draws, replayed to scene 12
    for _ in range(13):
        world = draw_scene(bench, rng, 0.01)
        goals = [draw_goal(bench, world, rng) for _ in range(5)]
    request = PlanRequest(goals[1], bench.start, arm=bench.arm, seed=121, world=world)
    return bench, world, request


def test_without_detours_no_direct_motion_is_free(blocked) -> None:
    _, _, request = blocked
    result = plan(request.replace(detours=False))
    assert result.status is PlanStatus.NOT_REACHED
    assert result.message.startswith('every direct motion found collides: ')
    assert 'via point' not in result.message


def test_a_detour_keeps_the_padding_by_python_fcl_and_rests_at_its_via_point(blocked) -> None:
    bench, world, request = blocked
    result = plan(request)
    assert result.success, result.message
    assert 'via 1 point' in result.message and len(result.via_points) == 1
    assert result.position_error_m <= 1e-9
    check = IndependentCheck(world, bench.urdf)
    assert check.violations(every_millisecond(result.trajectory(sample_period=1.0)),
                            START_TOLERANCE) == []
    trajectory = result.trajectory(sample_period=0.1)
    assert trajectory.duration == pytest.approx(result.motion_time_s, abs=1e-8)
    via = result.via_points[0]
    at = np.flatnonzero(np.all(np.abs(trajectory.positions - via) < 1e-12, axis=1))
    assert len(at) == 1                                      # a point of the message, at rest
    np.testing.assert_allclose(trajectory.at_time(trajectory.times[at])[0][0], via, atol=1e-12)
    np.testing.assert_array_equal(trajectory.positions[-1], result.joint_goal)
    assert result.trajectory_points(sample_period=0.1) == len(trajectory.times)


def test_a_detour_is_the_same_for_the_same_seed(blocked) -> None:
    _, _, request = blocked
    first, second = plan(request), plan(request)
    np.testing.assert_array_equal(first.joint_goal, second.joint_goal)
    np.testing.assert_array_equal(first.via_points[0], second.via_points[0])
    with pytest.raises(ValueError, match='detours must be true or false'):
        plan(request.replace(detours='yes'))
