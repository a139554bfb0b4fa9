# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Motions through via points where no direct motion is free, checked by python-fcl."""
from pathlib import Path

import numpy as np
import pytest
from trajplan_ros import plan, PlanStatus
from trajplan_ros.collision.free_motion import START_TOLERANCE
from trajplan_ros.kinematics import paper_arm
from trajplan_ros.motion.time_law import motion_times
from trajplan_ros.motion.trajectory import path_trajectory
from trajplan_ros.planning.planner import PlanRequest
from trajplan_ros.search.detour import _clipped
from trajplan_ros.search.goal import Goal
from trajplan_ros.search.objective import Objective
from trajplan_ros.tools.bench import ompl_peer
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
    return bench, world, request, goals


def test_without_detours_no_direct_motion_is_free(blocked) -> None:
    request = blocked[2]
    result = plan(request.replace(detours=False))
    assert result.status is PlanStatus.NOT_REACHED
    assert result.message.startswith('every direct motion found collides: ')
    assert 'via point' not in result.message


def test_a_detour_keeps_the_padding_by_python_fcl_and_rests_at_its_via_point(blocked) -> None:
    bench, world, request, _ = blocked
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
    request = blocked[2]
    first, second = plan(request), plan(request)
    np.testing.assert_array_equal(first.joint_goal, second.joint_goal)
    np.testing.assert_array_equal(first.via_points[0], second.via_points[0])
    with pytest.raises(ValueError, match='detours must be true or false'):
        plan(request.replace(detours='yes'))


def test_a_goal_with_a_free_direct_motion_gets_the_same_plan_with_detours(blocked) -> None:
    _, _, request, goals = blocked
    free = request.replace(goal=goals[0])
    without = plan(free.replace(detours=False))
    assert without.success and 'via' not in without.message
    with_detours = plan(free)
    np.testing.assert_array_equal(with_detours.joint_goal, without.joint_goal)
    assert with_detours.via_points == () and with_detours.message == without.message


def test_a_via_point_clipped_into_the_least_time_box_costs_nothing_over_the_direct_motion(
        ) -> None:
    obj = Objective(paper_arm(), Goal(np.array([0.15, 0.19, 0.17])), np.zeros(5), omega=0.2)
    before, after = np.zeros(5), np.array([0.9, 0.1, 0.9, -0.2, 0.0])
    via = np.array([-0.5, 1.2, 0.3, 0.8, 0.0])
    t1, t2, direct = (float(motion_times(obj.law, b[None], a)[0])
                      for a, b in ((before, via), (via, after), (before, after)))
    same = _clipped(obj, via, before, after, t1, t2)
    np.testing.assert_allclose(same, via, atol=1e-12)      # its own box holds it
    tight = _clipped(obj, via, before, after, direct * t1 / (t1 + t2), direct * t2 / (t1 + t2))
    total = sum(float(motion_times(obj.law, b[None], a)[0])
                for a, b in ((before, tight), (tight, after)))
    assert total == pytest.approx(direct, rel=1e-12)
    assert _clipped(obj, via, before, after, 0.5 * t1, 0.1 * t2) is None      # too short


def test_ompl_finds_a_path_this_check_and_python_fcl_call_free(blocked) -> None:
    pytest.importorskip('ompl')
    bench, world, request, _ = blocked
    result = plan(request)
    obj = Objective(bench.arm, request.goal, bench.start, omega=request.angular_velocity)
    ompl_peer.seed(7)
    peer = ompl_peer.rrt_connect(obj, world, result.law, result.motion.timing,
                                 result.joint_goal[None, :obj.arm.planned], 5.0, 0.2)
    assert peer is not None
    np.testing.assert_array_equal(peer.points[0], bench.start)
    np.testing.assert_allclose(peer.points[-1], result.joint_goal)
    path = path_trajectory(peer.points, result.law, result.motion.timing, sample_period=1.0)
    assert path.duration == pytest.approx(peer.duration, abs=1e-8)
    check = IndependentCheck(world, bench.urdf)
    assert check.violations(every_millisecond(path), START_TOLERANCE) == []
