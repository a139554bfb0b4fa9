# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""plan(): the library entry point used by the command and the node."""
import json

import numpy as np
import pytest

from trajplan_ros import DEFAULT_TOLERANCE, paper_arm, plan, PlanStatus
from trajplan_ros.planning.objective import Objective
from trajplan_ros.planning.paper_experiment import PAPER_TARGET
from trajplan_ros.planning.planner import ALGORITHMS

TARGET = PAPER_TARGET.tolist()
KEYS = {'goal', 'success', 'status', 'joint_goal', 'position_error_m', 'radial_error_rad',
        'motion_time_s', 'efficiency', 'iterations', 'evaluations', 'plan_time_s', 'algorithm',
        'mode', 'message'}


def test_paper_example_succeeds_with_the_exact_optimum():
    result = plan(TARGET, seed=1)
    assert result.status is PlanStatus.SUCCEEDED and result.success
    assert result.position_error_m <= 1e-9
    assert result.motion_time_s == pytest.approx(4.514270, rel=1e-3)
    assert result.joint_goal.shape == (5,)
    traj = result.trajectory(paper_arm())
    np.testing.assert_allclose(traj.positions[-1], result.joint_goal)
    assert traj.duration == pytest.approx(result.motion_time_s)


def test_to_dict_of_a_succeeded_plan_carries_its_values():
    result = plan(TARGET, seed=1)
    record = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    assert set(record) == KEYS
    assert record['goal'] == TARGET
    assert record['success'] is True and record['status'] == 'succeeded'
    assert record['joint_goal'] == result.joint_goal.tolist() and len(record['joint_goal']) == 5
    for key in ('position_error_m', 'motion_time_s', 'efficiency', 'plan_time_s'):
        assert record[key] == getattr(result, key) and isinstance(record[key], float)
    assert record['radial_error_rad'] is None                     # NaN in free mode
    assert record['iterations'] == result.iterations > 0
    assert record['evaluations'] == result.evaluations > 0
    assert (record['algorithm'], record['mode']) == ('iepso', 'free')
    assert record['message'] == result.message


def test_to_dict_of_a_rejected_plan_turns_nan_into_none():
    result = plan([np.nan, 0.1, 0.2])
    record = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    assert set(record) == KEYS
    assert record['goal'] == [None, 0.1, 0.2]
    assert record['success'] is False and record['status'] == 'rejected'
    assert record['joint_goal'] is None
    for key in ('position_error_m', 'radial_error_rad', 'motion_time_s', 'efficiency'):
        assert record[key] is None
    assert record['iterations'] == record['evaluations'] == 0
    assert record['plan_time_s'] == result.plan_time_s
    assert (record['algorithm'], record['mode']) == ('iepso', 'free')
    assert record['message'] == result.message and 'non-finite' in record['message']


@pytest.mark.parametrize('goal, start', [([0.5, 0.5, 0.5], None), ([np.nan, 0, 0], None),
                                         (TARGET, [0, 0, 0, 0, 9.0])])
def test_bad_requests_are_rejected_with_a_reason(goal, start):
    result = plan(goal, start)
    assert result.status is PlanStatus.REJECTED
    assert result.joint_goal is None and result.message
    assert '\n' not in result.message
    with pytest.raises(ValueError):
        result.trajectory(paper_arm())
    json.dumps(result.to_dict(), allow_nan=False)


def test_inside_the_sphere_but_unreachable_is_reported_not_reached():
    result = plan([0.36, 0.0, 0.05], seed=0)   # 0.363 m < reach bound 0.374 m, arm max ~0.35 m
    assert result.status is PlanStatus.NOT_REACHED
    assert result.position_error_m > 1e-3
    assert 'not reached' in result.message


def test_tolerance_decides_success():
    loose = plan([0.36, 0.0, 0.05], seed=0, tolerance=0.05)
    assert loose.success
    assert DEFAULT_TOLERANCE < loose.position_error_m <= 0.05   # missed, but within tolerance


@pytest.mark.parametrize('algorithm', ['pso', 'spso', 'ga', 'de'])
def test_comparison_algorithms_are_chosen_by_name(algorithm):
    result = plan(TARGET, algorithm=algorithm, seed=0, max_iter=60)
    assert result.algorithm == algorithm
    direct = ALGORITHMS[algorithm](Objective(paper_arm(), PAPER_TARGET, np.zeros(5)),
                                   max_iter=60, seed=0)
    assert result.joint_goal[:4].tobytes() == direct.x.tobytes()
    assert result.iterations == direct.nit and result.evaluations == direct.nfev


def test_bad_settings_raise():
    with pytest.raises(ValueError, match='unknown algorithm'):
        plan(TARGET, algorithm='annealing')
    with pytest.raises(ValueError):
        plan(TARGET, mode='sideways')
    with pytest.raises(ValueError):
        plan(TARGET, tolerance=-1)
