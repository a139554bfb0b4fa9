# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The exact reference (tests and benchmarks only) against the paper and doc/paper.md."""
import numpy as np
import pytest

from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.search.goal import Goal
from trajplan_ros.search.objective import Objective
from trajplan_ros.search.polish import polish
from trajplan_ros.tools.bench.cases import PAPER_TARGET as TARGET
from trajplan_ros.tools.bench.reference import exact_minimum

ARM = paper_arm()


@pytest.mark.parametrize('mode, minimum', [('free', 4.514270), ('radial', 6.691749)])
def test_paper_target_minimum_matches_doc(mode, minimum):
    ref = exact_minimum(ARM, TARGET, np.zeros(5), mode=mode)
    assert ref.motion_time_s == pytest.approx(minimum, abs=1e-6)
    p, u = ARM.tool(np.r_[ref.joint_goal, 0.0][None, :])
    assert np.linalg.norm(p[0] - TARGET) < 1e-12
    if mode == 'radial':
        assert u[0, 2] == pytest.approx(TARGET[2] / np.linalg.norm(TARGET), abs=1e-12)


def test_no_local_search_beats_the_reference():
    """Polish from 300 random configurations: nothing reaches the goal faster than the sweep."""
    rng = np.random.default_rng(5)
    for _ in range(3):
        goal = ARM.tool(rng.uniform(ARM.lower, ARM.upper, (1, 5)))[0][0]
        start = rng.uniform(ARM.lower, ARM.upper)
        ref = exact_minimum(ARM, goal, start)
        obj = Objective(ARM, Goal(goal), start)
        x = polish(obj, rng.uniform(obj.lower, obj.upper, (300, 4)), max_steps=30)
        ev = obj(x)
        reached = ev.error < 1e-10
        assert reached.sum() > 50
        assert ev.motion_time[reached].min() >= ref.motion_time_s * (1 - 1e-9)
        assert ev.motion_time[reached].min() <= ref.motion_time_s * (1 + 1e-6)


def test_other_arm_shapes_are_refused():
    arm = paper_arm()
    a, _, d = arm.dh
    other = ArmModel.from_dh(a=a, alpha=np.zeros(5), d=d, lower=arm.lower, upper=arm.upper,
                             planned=4)
    with pytest.raises(ValueError, match='shaped like'):
        exact_minimum(other, TARGET, np.zeros(5))
