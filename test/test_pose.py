# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Pose goals: the tool frame's position and whole orientation, on six and seven joints."""
import json
import re

import numpy as np
import pytest

from trajplan_ros import ArmModel, paper_arm, plan, PlanStatus
from trajplan_ros.kinematics.rotations import quaternions, rotation_matrix
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.search.goal import Goal
from trajplan_ros.search.objective import DEFAULT_OMEGA, Objective
from trajplan_ros.search.polish import Linearisation
from trajplan_ros.search.solution_curve import project_onto_curves, wrap_into
from trajplan_ros.tools.bench.cases import PUBLISHED
from trajplan_ros.tools.cli import main

UR5, PANDA = PUBLISHED['ur5'], PUBLISHED['panda']


def arm_of(published) -> ArmModel:
    return ArmModel.from_urdf(published.urdf, published.base_link, published.tip_link)


def pose_of(arm: ArmModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the tool frame's position and quaternion at q."""
    frame = arm.frames(q[None])[0, -1]
    return frame[:3, 3], quaternions(frame[None, :3, :3])[0]


def solutions(obj: Objective, rng: np.random.Generator, probes: int = 3000) -> np.ndarray:
    """Return the goal's joint solutions found by Newton steps from many random points."""
    x = rng.uniform(obj.lower, obj.upper, (probes, obj.arm.planned))
    for _ in range(25):                    # short steps, wrapped: many more probes converge
        here = Linearisation.at(obj, x, 1.0, newton_only=True)
        x = x + here.newton(here.c, np.full(probes, 0.5))
        wrap_into(x, obj.lower, obj.upper)
    x = np.clip(project_onto_curves(obj, x, 3), obj.lower, obj.upper)
    return x[obj.errors(obj.tool(x)) <= 1e-9]


def test_the_pose_error_is_the_angle_of_the_rotation_between_the_frames() -> None:
    arm = arm_of(UR5)
    rng = np.random.default_rng(5)
    position, quaternion = pose_of(arm, rng.uniform(-2, 2, 6))
    obj = Objective(arm, Goal(position, mode='pose', orientation=quaternion), np.zeros(6))
    goal = rotation_matrix(quaternion)
    for _ in range(20):
        q = rng.normal(size=4)
        reached = rotation_matrix(q / np.linalg.norm(q))
        tool = np.stack((position, reached @ obj.tool_frame[1], reached @ obj.tool_frame[2]))
        angle = np.arccos(np.clip((np.trace(goal.T @ reached) - 1) / 2, -1, 1))
        assert obj.angle_errors(tool[:, None])[0] == pytest.approx(angle, abs=1e-9)
    assert obj.angle_errors(np.stack((position, goal[:, 2], goal[:, 0]))[:, None])[0] < 1e-15


def test_a_six_joint_pose_is_the_fastest_of_its_solutions() -> None:
    arm = arm_of(UR5)
    rng = np.random.default_rng(7)
    for k in range(3):
        position, quaternion = pose_of(arm, rng.uniform(-np.pi, np.pi, 6))
        start = rng.uniform(-np.pi, np.pi, 6)
        result = plan(position, start, arm=arm, mode='pose', orientation=quaternion, seed=k)
        assert result.success, result.message
        assert result.position_error_m <= 1e-9 and result.orientation_error_rad <= 1e-9
        obj = Objective(arm, Goal(position, mode='pose', orientation=quaternion), start)
        fastest = obj.motion_time(solutions(obj, rng)).min()
        assert result.motion_time_s <= fastest * (1 + 1e-9), k


def test_a_seven_joint_pose_is_reached() -> None:
    arm = arm_of(PANDA)
    rng = np.random.default_rng(8)
    position, quaternion = pose_of(arm, rng.uniform(arm.lower, arm.upper))
    start = np.clip(np.zeros(7), arm.lower, arm.upper)
    result = plan(position, start, arm=arm, mode='pose', orientation=quaternion, seed=1)
    assert result.success, result.message
    assert result.position_error_m <= 1e-9 and result.orientation_error_rad <= 1e-9
    assert 'orientation 0 rad from the goal orientation' in result.message


def test_a_bad_or_missing_orientation_gets_a_reason() -> None:
    arm = arm_of(UR5)
    position, _ = pose_of(arm, np.full(6, 0.4))
    for orientation, reason in ((None, 'pose mode needs an orientation'),
                                ((0, 0, 0, 2), 'unit quaternion .* its norm is 2'),
                                ((0, 0, np.nan, 1), '4 finite numbers')):
        result = plan(position, arm=arm, mode='pose', orientation=orientation)
        assert result.status is PlanStatus.REJECTED
        assert re.search(reason, result.message), result.message
    with pytest.raises(ValueError, match='an orientation is for pose and approach modes, not fr'):
        plan(position, arm=arm, orientation=(0, 0, 0, 1))


def test_a_pose_the_arm_cannot_take_is_not_reached_with_the_best_angle() -> None:
    # the paper's four-joint arm cannot turn its tool about the tool axis
    arm = paper_arm()
    position, quaternion = pose_of(arm, np.array([0.3, 0.5, -0.4, 0.2, 0.0]))
    turned = rotation_matrix(quaternion) @ rotation_matrix((0, 0, np.sin(0.2), np.cos(0.2)))
    result = plan(position, arm=arm, mode='pose', seed=2,
                  orientation=quaternions(turned[None])[0])
    assert result.status is PlanStatus.NOT_REACHED
    assert 'from the goal orientation' in result.message


def test_trajplan_plans_a_goals_csv_of_poses(tmp_path, capsys) -> None:
    arm = paper_arm()
    urdf = tmp_path / 'paper_arm.urdf'
    urdf.write_text(urdf_xml(arm, velocity=DEFAULT_OMEGA))
    position, quaternion = pose_of(arm, np.array([0.3, 0.5, -0.4, 0.2, 0.0]))
    goals = tmp_path / 'goals.csv'
    cells = ','.join(str(float(v)) for v in [*position, *quaternion])
    goals.write_text(f'x,y,z,qx,qy,qz,qw\n{cells}\n')
    assert main(['plan', '--urdf', str(urdf), '--tip-link', 'tool_link', '--goals', str(goals),
                 '--json']) == 0
    record = json.loads(capsys.readouterr().out)
    assert record['mode'] == 'pose' and record['orientation_error_rad'] <= 1e-9
