# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Tolerances as regions: the least motion time inside the goal's tolerances."""
from __future__ import annotations

import numpy as np
import pytest

from trajplan_ros import ArmModel, paper_arm, plan, PlanStatus
from trajplan_ros.kinematics.rotations import (quaternion_of_turn, quaternions, rotation_matrix,
                                               turn_of_quaternion)
from trajplan_ros.search.goal import Goal, Mode
from trajplan_ros.search.objective import Objective
from trajplan_ros.search.polish import polish
from trajplan_ros.search.region import multipliers, Region, target_gradient
from trajplan_ros.tools.bench.cases import PUBLISHED
from trajplan_ros.tools.bench.chain_bench import region_reference, tolerance_region
from trajplan_ros.tools.cli import main

GOAL = np.array([0.151171, 0.19162, 0.172124])


def published(name: str) -> ArmModel:
    """Return a published arm's chain as the bench plans it."""
    a = PUBLISHED[name]
    return ArmModel.from_urdf(str(a.urdf), a.base_link, a.tip_link)


def _least_time(obj: Objective, x: np.ndarray) -> float:
    """Return the motion time of the exact plan to ``obj``'s goal polished from x."""
    return float(obj.motion_time(polish(obj, x[None], max_steps=60)[0][None])[0])


def test_the_multipliers_are_the_gradient_of_the_least_time_by_the_goal() -> None:
    arm, start = paper_arm(), np.array([0.3, -0.2, 0.4, 0.1, 0.0])
    result = plan(GOAL, start, seed=2)
    obj = Objective(arm, Goal(GOAL), start)
    x = result.joint_goal[:obj.arm.planned]
    gradient = target_gradient(obj, x, multipliers(obj, x)).shift
    h = 1e-5
    for k in range(3):
        step = h * np.eye(3)[k]
        ahead = _least_time(Objective(arm, Goal(GOAL + step), start), x)
        behind = _least_time(Objective(arm, Goal(GOAL - step), start), x)
        assert (ahead - behind) / (2 * h) == pytest.approx(gradient[k], rel=1e-3, abs=1e-3)


def test_a_position_tolerance_is_a_ball_whose_fastest_point_the_plan_reaches() -> None:
    exact = plan(GOAL, seed=1)
    loose = plan(GOAL, seed=1, tolerance=0.01)
    assert loose.status is PlanStatus.SUCCEEDED, loose.message
    assert loose.position_error_m == pytest.approx(0.01, rel=1e-4)
    assert loose.motion_time_s < exact.motion_time_s * (1 - 1e-3)
    obj = Objective(paper_arm(), Goal(GOAL), np.zeros(5))
    reference, _ = region_reference(obj, Region(0.01, 0.0), np.random.default_rng(0), 4,
                                    exact.joint_goal[:obj.arm.planned])
    assert loose.motion_time_s <= reference * (1 + 1e-4)


def test_the_default_tolerances_reach_the_goal_itself() -> None:
    result = plan(GOAL, seed=1)
    assert result.position_error_m < 1e-12
    radial = plan(GOAL, seed=1, mode='radial')
    assert radial.position_error_m < 1e-12 and radial.axis_error_rad < 1e-9


@pytest.mark.parametrize('goal', [(0.15, -0.1, 0.05), (0.25, 0.0, 0.08), (0.1, 0.2, 0.05)])
def test_a_pick_from_above_takes_the_fastest_axis_in_its_cone(
        goal: tuple[float, float, float]) -> None:
    arm = published('so101')
    start = np.clip(np.full(arm.n_joints, 0.3), arm.lower, arm.upper)
    obj = Objective(arm, Goal(np.array(goal), mode='approach'), start)
    centre = plan(goal, start, arm=arm, mode='approach', seed=3, axis_tolerance=1e-6)
    before = np.inf
    for tolerance in (0.001, 0.01, 0.05):
        result = plan(goal, start, arm=arm, mode='approach', seed=3, axis_tolerance=tolerance)
        assert result.status is PlanStatus.SUCCEEDED, result.message
        assert result.axis_error_rad <= tolerance and result.position_error_m <= 1e-6
        assert result.motion_time_s <= before                 # a larger cone: no slower
        reference, _ = region_reference(obj, Region(0.0, tolerance),
                                        np.random.default_rng(0), 4,
                                        centre.joint_goal[:obj.arm.planned])
        assert result.motion_time_s <= reference * (1 + 1e-3)
        before = result.motion_time_s


@pytest.mark.xfail(strict=True, reason='a faster pose in the cone turns the wrist roll far '
                   'from its start (another branch): the region is searched from the plan '
                   'to its centre only')
def test_a_cone_whose_fastest_axis_lies_on_another_branch() -> None:
    arm = published('so101')
    start = np.clip(np.full(arm.n_joints, 0.3), arm.lower, arm.upper)
    goal = np.array((0.2, 0.1, 0.02))
    centre = plan(goal, start, arm=arm, mode='approach', seed=3, axis_tolerance=1e-6)
    result = plan(goal, start, arm=arm, mode='approach', seed=3, axis_tolerance=0.01)
    obj = Objective(arm, Goal(goal, mode='approach'), start)
    reference, _ = region_reference(obj, Region(0.0, 0.01), np.random.default_rng(0), 4,
                                    centre.joint_goal[:obj.arm.planned])
    assert result.motion_time_s <= reference * (1 + 1e-3)


def test_a_pose_takes_the_fastest_orientation_within_its_tolerance() -> None:
    arm = published('panda')
    q = np.array([0.3, -0.5, 0.2, -2.0, 0.1, 1.8, 0.6])
    frame = arm.frames(q[None])[0, -1]
    orientation = quaternions(frame[None, :3, :3])[0]
    start = np.clip(np.zeros(arm.n_joints), arm.lower, arm.upper)
    exact = plan(frame[:3, 3], start, arm=arm, mode='pose', orientation=orientation, seed=4)
    result = plan(frame[:3, 3], start, arm=arm, mode='pose', orientation=orientation, seed=4,
                  orientation_tolerance=0.01)
    assert result.status is PlanStatus.SUCCEEDED, result.message
    assert result.orientation_error_rad <= 0.01 and result.position_error_m <= 1e-6
    assert result.motion_time_s < exact.motion_time_s
    obj = Objective(arm, Goal(frame[:3, 3], mode='pose', orientation=orientation), start)
    reference, _ = region_reference(obj, Region(0.0, 0.01), np.random.default_rng(0), 2,
                                    exact.joint_goal)
    assert result.motion_time_s <= reference * (1 + 1e-3)


def test_the_bench_takes_the_tolerances_by_their_names(capsys: pytest.CaptureFixture) -> None:
    assert tolerance_region({'orientation_tolerance': 0.01}, Mode.POSE) == Region(0.0, 0.01)
    assert tolerance_region({'axis_tolerance': 0.01, 'tolerance': 0.002},
                            Mode.APPROACH) == Region(0.002, 0.01)
    assert tolerance_region({'axis_tolerance': 0.01}, Mode.FREE) == Region(0.0, 0.0)
    assert main(['bench', '--goals', '2', '--axis-tolerance', '0.01']) == 2
    assert 'tolerances are benchmarked on a URDF chain' in capsys.readouterr().err


def test_a_turn_and_its_quaternion_are_one_rotation() -> None:
    for turn in (np.zeros(3), np.array([1e-9, 0.0, 0.0]), np.array([0.3, -0.2, 0.05])):
        q = quaternion_of_turn(turn)
        assert turn_of_quaternion(q) == pytest.approx(turn, abs=1e-15)
        assert np.linalg.norm(q) == pytest.approx(1.0, abs=1e-15)
    axis = np.array([0.0, 0.0, 0.5])                  # half a radian about z
    assert rotation_matrix(quaternion_of_turn(axis)) @ [1.0, 0.0, 0.0] == pytest.approx(
        [np.cos(0.5), np.sin(0.5), 0.0], abs=1e-15)


def test_a_start_already_inside_the_region_is_the_plan_without_a_fault() -> None:
    # the arm stopped with its tool on the region's edge: no joint moves, so none fixes the
    # scale of the multipliers (a division by a zero slope before)
    start = np.array([0.8987569478698615, 0.13059056017413162, 0.8987569478698952,
                      -0.20651430411764007, 0.0])
    result = plan((0.151171, 0.19162, 0.172124), start, seed=0, tolerance=0.001)
    assert result.success, result.message
    assert result.motion_time_s < 1e-6 and result.position_error_m <= 0.001
