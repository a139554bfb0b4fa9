# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The URDF chain bench: its reference, its independent FK and the command (small sizes)."""
from __future__ import annotations

import numpy as np
import pytest

from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.search.goal import Goal, Mode
from trajplan_ros.search.objective import DEFAULT_OMEGA, Objective
from trajplan_ros.tools.bench.cases import PUBLISHED
from trajplan_ros.tools.bench.chain_bench import (draw_chain_cases, IndependentFk,
                                                  minimax_reference)
from trajplan_ros.tools.bench.reference import exact_minimum
from trajplan_ros.tools.cli import main


def test_the_reference_is_feasible_and_finds_the_exact_minimum_on_the_paper_arm() -> None:
    arm = paper_arm()
    rng = np.random.default_rng(4)
    for k in range(5):
        goal = arm.tool(rng.uniform(arm.lower, arm.upper, (1, 5)))[0][0]
        obj = Objective(arm, Goal(goal), np.zeros(5))
        time, x = minimax_reference(obj, rng, starts=24)
        exact = exact_minimum(arm, goal, np.zeros(5)).motion_time_s
        assert x is not None
        assert np.linalg.norm(obj.tool(x[None])[0][0] - goal) <= 1e-9
        assert time >= exact * (1 - 1e-9)                       # a feasible pose, never faster
        assert time <= exact * (1 + 1e-3), k                    # and here it finds the optimum


def test_the_independent_fk_is_yourdfpys_and_agrees_with_ours() -> None:
    so101 = PUBLISHED['so101']
    arm = ArmModel.from_urdf(so101.urdf, so101.base_link, so101.tip_link,
                             tool_offset=(0.0, 0.01, 0.02), tool_axis=(1.0, 0.0, 0.0))
    fk = IndependentFk(str(so101.urdf), arm)
    frame = np.stack((arm.tool_point, arm.tool_axis, (0.0, 1.0, 0.0)))
    for q in np.random.default_rng(1).uniform(arm.lower, arm.upper, (10, 5)):
        p, u, w = fk.tool(q, frame)
        ours = arm.tool(q[None])
        assert np.allclose(p, ours[0][0], atol=1e-12) and np.allclose(u, ours[1][0], atol=1e-12)
        tip = arm.frames(q[None])[0, -1]
        assert np.allclose(w, tip[:3, 1], atol=1e-12)


def test_the_independent_fk_follows_moves_below_its_scene_graphs_tolerance() -> None:
    # trimesh keeps an edge whose new transform is allclose (1e-8) to the old one
    so101 = PUBLISHED['so101']
    arm = ArmModel.from_urdf(so101.urdf, so101.base_link, so101.tip_link)
    fk = IndependentFk(str(so101.urdf), arm)
    frame = np.stack((arm.tool_point, arm.tool_axis))
    q = np.array([1.5, arm.lower[1], -1.4, -1.3, 1.6])
    fk.tool(q, frame)
    q[1] += 5e-9
    assert np.linalg.norm(fk.tool(q, frame)[0] - arm.tool(q[None])[0][0]) <= 1e-14


def test_radial_goals_without_a_radial_pose_are_dropped() -> None:
    so101 = PUBLISHED['so101']
    arm = ArmModel.from_urdf(so101.urdf, so101.base_link, so101.tip_link)
    cases, dropped = draw_chain_cases(arm, 2, mode=Mode.RADIAL, random_starts=True, seed=0,
                                      starts=6)
    assert len(cases) == 2 and dropped >= 0
    for case in cases:
        obj = Objective(arm, Goal(case.goal, mode=Mode.RADIAL), case.start)
        p, u = obj.tool(case.reference_q[None, : obj.arm.planned])
        assert np.linalg.norm(p[0] - case.goal) <= 1e-9 and obj.axis_angle(u)[0] <= 1e-9


def test_bench_on_a_urdf_prints_every_row(tmp_path, capsys) -> None:
    urdf = tmp_path / 'paper_arm.urdf'
    urdf.write_text(urdf_xml(paper_arm(), velocity=DEFAULT_OMEGA))
    argv = ['bench', '--urdf', str(urdf), '--tip-link', 'tool_link', '--goals', '2',
            '--reference-starts', '6', '--quiet', '--random-starts']
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert '2 goals, 5-joint chain base_link -> tool_link' in out
    for row in ('iepso', 'scipy-de', 'pyswarms', 'ikpy'):
        assert f'\n{row} ' in out
    assert 'reference motion time: median' in out


@pytest.mark.parametrize('argv, reason', [
    (['--only', 'no-solution'], '--urdf draws its own goals'),
    (['--paper'], '--urdf draws its own goals'),
])
def test_bench_on_a_urdf_refuses_options_of_the_paper_bench(argv, reason, capsys) -> None:
    so101 = PUBLISHED['so101']
    assert main(['bench', '--urdf', str(so101.urdf), '--tip-link', so101.tip_link, *argv,
                 '--quiet']) == 2
    assert reason in capsys.readouterr().err


def test_ikpy_needs_a_urdf(capsys) -> None:
    assert main(['bench', '--algorithms', 'ikpy', '--goals', '1', '--quiet']) == 2
    assert 'ikpy needs --urdf' in capsys.readouterr().err
