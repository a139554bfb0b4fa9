# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Joint goals: the motion to given joint angles, direct or around obstacles, never elsewhere."""
from pathlib import Path

import numpy as np
import pytest
from trajplan_ros import Goal, plan, PlanStatus
from trajplan_ros.collision.free_motion import START_TOLERANCE
from trajplan_ros.kinematics import paper_arm
from trajplan_ros.motion.time_law import motion_times
from trajplan_ros.planning.planner import _warm_up_world, PlanRequest
from trajplan_ros.tools.bench.clearance import IndependentCheck
from trajplan_ros.tools.bench.collision_bench import (BenchArm, draw_goal, draw_scene,
                                                      every_millisecond)

ARM = paper_arm()
GOAL = np.array([0.5, -0.3, 0.4, 0.2, 0.1])


def test_a_joint_goal_is_reached_exactly_in_the_time_of_eq_10() -> None:
    start = np.array([0.1, 0.0, -0.2, 0.0, 0.3])
    result = plan(PlanRequest(Goal(joint_goal=GOAL), start))
    assert result.success, result.message
    assert result.message.startswith('reached the joint goal in 3.0000 s of motion')
    np.testing.assert_array_equal(result.joint_goal, GOAL)
    law = result.motion.time_law(ARM, result.angular_velocity)
    assert result.motion_time_s == pytest.approx(motion_times(law, GOAL[None], start)[0])
    np.testing.assert_allclose(result.goal, ARM.tool(GOAL[None])[0][0], atol=1e-12)
    trajectory = result.trajectory(sample_period=0.1)
    np.testing.assert_array_equal(trajectory.positions[-1], GOAL)
    assert trajectory.duration == pytest.approx(result.motion_time_s, abs=1e-9)


def test_the_planned_joints_alone_leave_the_held_ones_at_their_start() -> None:
    start = np.array([0.0, 0.0, 0.0, 0.0, 0.7])
    result = plan(PlanRequest(Goal(joint_goal=GOAL[:ARM.planned]), start))
    assert result.success, result.message
    np.testing.assert_array_equal(result.joint_goal, [*GOAL[:ARM.planned], 0.7])


@pytest.mark.parametrize('joint_goal, reason', [
    ([5.0, 0.0, 0.0, 0.0, 0.0], 'joint goal joint1 = 5 rad is outside its limits'),
    ([0.1, 0.2, 0.3], 'a joint goal needs 5 joint angles (or the 4 planned ones), got 3'),
    ([0.1, np.nan, 0.3, 0.0, 0.0], 'joint goal has a non-finite angle'),
])
def test_a_joint_goal_the_arm_cannot_take_is_rejected_with_the_reason(joint_goal,
                                                                      reason) -> None:
    result = plan(PlanRequest(Goal(joint_goal=joint_goal)))
    assert result.status is PlanStatus.REJECTED and result.joint_goal is None
    assert result.message.startswith(reason)


def test_a_joint_goal_whose_pose_collides_is_rejected_naming_the_pair() -> None:
    world = _warm_up_world()                     # a box at (0.12, -0.12, 0.1)
    into = plan(PlanRequest((0.12, -0.12, 0.1), seed=0)).joint_goal
    result = plan(PlanRequest(Goal(joint_goal=into), world=world))
    assert result.status is PlanStatus.REJECTED
    assert result.message.startswith('the joint goal is in collision: ')
    assert 'box' in result.clearance_pair


def test_a_blocked_joint_goal_gets_a_detour_to_it_that_python_fcl_calls_free(
        tmp_path: Path) -> None:
    bench = BenchArm.load('paper', tmp_path)
    rng = np.random.default_rng(12)             # the detour tests' scene: no direct motion free
    for _ in range(13):
        world = draw_scene(bench, rng, 0.01)
        goals = [draw_goal(bench, world, rng) for _ in range(5)]
    around = plan(PlanRequest(goals[1], bench.start, arm=bench.arm, seed=121, world=world))
    assert around.success and around.via_points, around.message
    request = PlanRequest(Goal(joint_goal=around.joint_goal), bench.start, arm=bench.arm,
                          seed=0, world=world)
    direct = plan(request.replace(detours=False))
    assert direct.status is PlanStatus.NOT_REACHED
    assert direct.message.startswith('the direct motion to the joint goal collides: ')
    result = plan(request)
    assert result.success and result.via_points, result.message
    np.testing.assert_array_equal(result.joint_goal, around.joint_goal)
    check = IndependentCheck(world, bench.urdf)
    assert check.violations(every_millisecond(result.trajectory(sample_period=1.0)),
                            START_TOLERANCE) == []
