# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Arms of two joints, as small vendor files describe them: planar, idle or locked joints."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from trajplan_ros import ArmModel, plan, PlanStatus
from trajplan_ros.search.goal import Goal
from trajplan_ros.search.objective import Objective
from trajplan_ros.tools.bench.chain_bench import minimax_reference

#: Two joints about parallel z axes (a planar arm), 0.1 m apart, a tool link 0.08 m further.
PLANAR = """<robot name="planar2">
  <link name="base"/><link name="upper"/><link name="lower"/><link name="tool"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="{lo}" upper="{hi}" effort="1" velocity="1"/></joint>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="lower"/><origin xyz="0.1 0 0"/><axis xyz="0 0 1"/>
    <limit lower="{lo}" upper="{hi}" effort="1" velocity="1"/></joint>
  <joint name="flange" type="fixed">
    <parent link="lower"/><child link="tool"/><origin xyz="0.08 0 0"/></joint>
</robot>"""


def planar(tip: str, lo: float = -3.14, hi: float = 3.14) -> ArmModel:
    """Return the planar arm to ``tip``: 'tool', or 'lower' (the elbow cannot move it)."""
    return ArmModel.from_urdf(PLANAR.format(lo=lo, hi=hi), 'base', tip)


def drawn(arm: ArmModel, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Return a goal (the tool position of a random in-limit pose) and a random start."""
    q = rng.uniform(arm.lower, arm.upper, (2, arm.n_joints))
    return arm.tool(q[:1])[0][0], q[1]


def test_a_planar_arm_reaches_its_goals_as_fast_as_the_reference() -> None:
    """Three conditions on two joints, one of them never changing: SLSQP's reference copes."""
    arm = planar('tool')
    rng = np.random.default_rng(5)
    for k in range(12):
        goal, start = drawn(arm, rng)
        time, best = minimax_reference(Objective(arm, Goal(goal), start), rng, starts=12)
        assert best is not None, k
        result = plan(goal, start, arm=arm, seed=k)
        assert result.success, (k, result.message)
        assert result.motion_time_s <= time * (1 + 1e-6), k


def test_a_joint_that_cannot_move_the_tool_keeps_its_start() -> None:
    """The tool point on the elbow's axis: only the shoulder is planned, the elbow is held."""
    arm = planar('lower')
    assert arm.without_idle_tail(False).planned == 1
    rng = np.random.default_rng(6)
    for k in range(40):
        goal, start = drawn(arm, rng)
        result = plan(goal, start, arm=arm, seed=k)
        assert result.success, (k, result.message)
        assert result.joint_goal[1] == start[1], k
        obj = Objective(arm, Goal(goal), start)
        time, _ = minimax_reference(obj, rng, starts=4)
        assert result.motion_time_s <= time * (1 + 1e-6), k


def test_goals_at_full_stretch_are_never_refused() -> None:
    """Every tool point lies on a circle as wide as the reach: rounding must not refuse it."""
    arm = planar('lower')
    rng = np.random.default_rng(7)
    refused = [k for k in range(300)
               if plan(drawn(arm, rng)[0], np.zeros(2), arm=arm, seed=k).status
               is PlanStatus.REJECTED]
    assert refused == []


def test_an_arm_whose_joints_cannot_move_plans_without_warnings() -> None:
    """Limits lower = upper (a placeholder in some files): only the home point is reached."""
    arm = planar('tool', 0.0, 0.0)
    home = arm.tool(np.zeros((1, 2)))[0][0]
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        assert plan(home, np.zeros(2), arm=arm, seed=1).status is PlanStatus.SUCCEEDED
        assert (plan(home * 0.9, np.zeros(2), arm=arm, seed=1).status
                is PlanStatus.NOT_REACHED)
        assert (plan(home, np.zeros(2), arm=arm, seed=1, mode='radial').status
                is PlanStatus.NOT_REACHED)


@pytest.mark.parametrize('tip', ['tool', 'lower'])
def test_the_reference_finds_poses_on_two_joint_arms(tip: str) -> None:
    """SLSQP fails on redundant equalities; the bench's reference must not (``local_minimax``)."""
    arm = planar(tip)
    rng = np.random.default_rng(8)
    for _ in range(5):
        goal, start = drawn(arm, rng)
        time, best = minimax_reference(Objective(arm, Goal(goal), start), rng, starts=4)
        assert best is not None
        assert np.linalg.norm(arm.tool(Objective(arm, Goal(goal), start).full(best))[0][0]
                              - goal) <= 1e-9
