# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Approach mode (the tool axis along a direction, e.g. a pick from above), start margins."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from trajplan_ros import ArmModel, paper_arm, plan, PlanStatus
from trajplan_ros.search.goal import Goal
from trajplan_ros.search.objective import Objective
from trajplan_ros.tools.bench.cases import PUBLISHED
from trajplan_ros.tools.bench.chain_bench import minimax_reference
from trajplan_ros.tools.cli import main

DOWN = np.array([0.0, 0.0, -1.0])


def published(name: str) -> ArmModel:
    """Return a published arm's chain as the bench plans it."""
    a = PUBLISHED[name]
    return ArmModel.from_urdf(str(a.urdf), a.base_link, a.tip_link)


@pytest.mark.parametrize('name, goal', [('so101', (0.2, 0.1, 0.02)), ('so101', (0.1, 0.2, 0.05)),
                                        ('ur5', (0.3, 0.2, 0.1))])
def test_a_pick_from_above_points_down_and_is_as_fast_as_the_reference(
        name: str, goal: tuple[float, float, float]) -> None:
    arm = published(name)
    start = np.clip(np.zeros(arm.n_joints), arm.lower, arm.upper)
    result = plan(goal, start, arm=arm, mode='approach', seed=3)
    assert result.status is PlanStatus.SUCCEEDED, result.message
    p, u = arm.tool(result.joint_goal[None])
    assert np.linalg.norm(p[0] - goal) <= 1e-6
    angle = np.arctan2(np.linalg.norm(np.cross(u[0], DOWN)), u[0] @ DOWN)
    assert angle == pytest.approx(result.axis_error_rad, abs=1e-12)
    assert result.axis_error_rad <= 1e-3 and 'from the approach direction' in result.message
    obj = Objective(arm, Goal(np.array(goal), mode='approach'), start)
    reference, _ = minimax_reference(obj.in_plane() or obj, np.random.default_rng(0), starts=8)
    assert result.motion_time_s <= reference * (1 + 1e-3)


def test_an_approach_the_arm_cannot_take_is_not_reached_with_the_best_angle() -> None:
    result = plan((0.2, 0.1, 0.02), arm=published('so101'), mode='approach',
                  approach=(0.0, 0.0, 1.0), seed=1)      # pointing up at the table: no pose
    assert result.status is PlanStatus.NOT_REACHED
    assert 'from the approach direction' in result.message
    with pytest.raises(ValueError, match='approach must be 3 finite numbers, not all zero'):
        plan((0.2, 0.1, 0.02), mode='approach', approach=(0.0, 0.0, 0.0))


def test_a_start_a_little_outside_its_limits_is_planned_from_further_out_refused() -> None:
    arm, goal = paper_arm(), (0.151171, 0.19162, 0.172124)
    start = np.zeros(5)
    start[1] = arm.lower[1] - 0.03                    # a calibrated arm reading past its limit
    result = plan(goal, start, seed=1)
    assert result.success and 'joint2 = -1.6008 rad is outside its limits' in result.message
    assert 'the motion brings it inside' in result.message
    traj = result.trajectory()
    assert traj.positions[0][1] < arm.lower[1]          # 0.1 s in: still outside, from where it is
    assert arm.lower[1] <= traj.positions[-1][1] <= arm.upper[1]
    start[1] = arm.lower[1] - 0.13
    refused = plan(goal, start, seed=1)
    assert refused.status is PlanStatus.REJECTED
    assert 'more than the start_limit_margin 0.05 rad' in refused.message
    assert plan(goal, start, seed=1, start_limit_margin=0.2).success


def test_trajplan_plans_approach_goals_and_reads_a_csv_header(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    urdf = ['--urdf', str(PUBLISHED['so101'].urdf), '--tip-link', 'gripper_frame_link']
    assert main(['plan', '0.2', '0.1', '0.02', '--approach', '0', '0', '-1', '--json',
                 *urdf]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record['mode'] == 'approach' and record['axis_error_rad'] <= 1e-3
    names = ['shoulder_lift', 'shoulder_pan', 'elbow_flex', 'wrist_flex', 'wrist_roll']
    goals = tmp_path / 'goals.csv'
    goals.write_text('x,y,z,ax,ay,az,' + ','.join(names) + '\n'
                     '0.2,0.1,0.02,0,0,-1,0.1,0,0,0,0\n'
                     '0.2,0.1,0.02,0,0,0,0,0,0,0,0\n', encoding='utf-8')
    assert main(['plan', '--goals', str(goals), '--json', *urdf]) == 1
    first, second = (json.loads(line) for line in capsys.readouterr().out.splitlines())
    assert first['success'] and first['mode'] == 'approach'
    assert second['status'] == 'rejected' and 'approach must be' in second['message']
    start = dict(zip(record['joint_names'], [0.0] * 5), shoulder_lift=0.1)
    again = plan((0.2, 0.1, 0.02), [start[n] for n in record['joint_names']],
                 arm=ArmModel.from_urdf(str(PUBLISHED['so101'].urdf), None,
                                        'gripper_frame_link'), mode='approach', seed=0)
    assert first['joint_goal'] == again.joint_goal.tolist()     # the columns by joint name


def test_only_a_pan_and_pitch_arm_first_holds_the_in_plane_component() -> None:
    goal, down = np.array([0.2, 0.1, 0.05]), 'approach'
    for name, expected in (('so101', True), ('ur5', False), ('panda', False)):
        arm = published(name)
        start = np.clip(np.zeros(arm.n_joints), arm.lower, arm.upper)
        obj = Objective(arm, Goal(goal, mode=down), start)
        assert obj.pan_and_pitch() is expected, name
        assert (obj.in_plane() is not None) is expected
    assert Objective(paper_arm(), Goal(goal, mode=down), np.zeros(5)).pan_and_pitch()
    assert Objective(paper_arm(), Goal(goal), np.zeros(5)).in_plane() is None        # free mode
