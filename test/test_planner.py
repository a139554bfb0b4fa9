"""plan(): the library entry point used by the command and the node."""
import json

import numpy as np
import pytest

from trajplan_ros import PlanStatus, paper_arm, plan

TARGET = [0.151171, 0.19162, 0.172124]


def test_paper_example_succeeds_with_the_exact_optimum():
    result = plan(TARGET, seed=1)
    assert result.status is PlanStatus.SUCCEEDED and result.success
    assert result.position_error_m <= 1e-9
    assert result.motion_time_s == pytest.approx(4.514270, rel=1e-3)
    assert result.joint_goal.shape == (5,)
    traj = result.trajectory(paper_arm())
    np.testing.assert_allclose(traj.positions[-1], result.joint_goal)
    assert traj.duration == pytest.approx(result.motion_time_s)


def test_to_dict_is_json_with_the_documented_keys():
    record = json.loads(json.dumps(plan(TARGET, seed=1).to_dict()))
    for key in ('goal', 'success', 'joint_goal', 'position_error_m', 'motion_time_s', 'efficiency',
                'iterations', 'plan_time_s', 'message'):
        assert key in record


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
    result = plan([0.36, 0.0, 0.05], seed=0)        # 0.363 m < reach bound 0.374 m, arm max ~0.35 m
    assert result.status is PlanStatus.NOT_REACHED
    assert result.position_error_m > 1e-3
    assert 'not reached' in result.message


def test_tolerance_decides_success():
    loose = plan([0.36, 0.0, 0.05], seed=0, tolerance=0.05)
    assert loose.success


@pytest.mark.parametrize('algorithm', ['pso', 'spso', 'ga', 'de'])
def test_comparison_algorithms_are_chosen_by_name(algorithm):
    result = plan(TARGET, algorithm=algorithm, seed=0, max_iter=60)
    assert result.algorithm == algorithm and result.joint_goal is not None


def test_bad_settings_raise():
    with pytest.raises(ValueError, match='unknown algorithm'):
        plan(TARGET, algorithm='annealing')
    with pytest.raises(ValueError):
        plan(TARGET, mode='sideways')
    with pytest.raises(ValueError):
        plan(TARGET, tolerance=-1)
