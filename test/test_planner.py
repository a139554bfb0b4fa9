# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""plan(): the library entry point used by the command and the node."""
import itertools
import json
import time
from typing import Callable

import numpy as np
import pytest

from trajplan_ros import (ArmModel, DEFAULT_TOLERANCE, MotionProfile, paper_arm, plan,
                          PlanRequest, PlanStatus)
from trajplan_ros.planning import planner
from trajplan_ros.planning.planner import ALGORITHMS, describe_residual
from trajplan_ros.search.goal import Goal, Mode
from trajplan_ros.search.iepso import iepso
from trajplan_ros.search.objective import Objective
from trajplan_ros.tools.bench.cases import draw_cases, PAPER_TARGET
from trajplan_ros.tools.bench.reference import _solutions, radial_angle

TARGET = PAPER_TARGET.tolist()
#: Inside the reach sphere but out of reach: IEPSO searches it for dozens of iterations.
FAR = [0.36, 0.0, 0.05]
KEYS = {'goal', 'success', 'status', 'joint_goal', 'position_error_m', 'axis_error_rad',
        'orientation_error_rad',
        'motion_time_s', 'efficiency', 'iterations', 'evaluations', 'plan_time_s', 'algorithm',
        'mode', 'profile', 'timing', 'clearance_m', 'clearance_pair', 'via_points',
        'message'}


def test_paper_example_succeeds_with_the_exact_optimum():
    result = plan(TARGET, seed=1)
    assert result.status is PlanStatus.SUCCEEDED and result.success
    assert result.position_error_m <= 1e-9
    assert result.motion_time_s == pytest.approx(4.514270, rel=1e-3)
    assert result.joint_goal.shape == (5,)
    traj = result.trajectory()                 # the result knows its arm's joints and limits
    np.testing.assert_allclose(traj.positions[-1], result.joint_goal)
    assert traj.duration == pytest.approx(result.motion_time_s)
    assert traj.joint_names == paper_arm().joint_names
    np.testing.assert_array_equal(result.trajectory(paper_arm()).positions, traj.positions)
    other = ArmModel.from_dh(np.full(5, 0.1), np.zeros(5), np.zeros(5), lower=np.full(5, -3),
                             upper=np.full(5, 3), joint_names=[f'other{i}' for i in range(5)])
    with pytest.raises(ValueError, match='the plan is for joints'):
        result.trajectory(other)


def test_to_dict_of_a_succeeded_plan_carries_its_values():
    result = plan(TARGET, seed=1)
    record = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    assert set(record) == KEYS
    assert record['goal'] == TARGET
    assert record['success'] is True and record['status'] == 'succeeded'
    assert record['joint_goal'] == result.joint_goal.tolist() and len(record['joint_goal']) == 5
    for key in ('position_error_m', 'motion_time_s', 'efficiency', 'plan_time_s'):
        assert record[key] == getattr(result, key) and isinstance(record[key], float)
    assert record['axis_error_rad'] is None                     # NaN in free mode
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
    for key in ('position_error_m', 'axis_error_rad', 'motion_time_s', 'efficiency'):
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
        result.trajectory()
    json.dumps(result.to_dict(), allow_nan=False)


def test_inside_the_sphere_but_unreachable_is_reported_not_reached():
    result = plan(FAR, seed=0)   # 0.363 m < reach bound 0.374 m, arm max ~0.35 m
    assert result.status is PlanStatus.NOT_REACHED
    assert result.position_error_m > 1e-3
    assert 'not reached' in result.message


def test_tolerance_decides_success():
    loose = plan(FAR, seed=0, tolerance=0.05)
    assert loose.success
    assert DEFAULT_TOLERANCE < loose.position_error_m <= 0.05   # missed, but within tolerance


@pytest.mark.parametrize('algorithm', ['pso', 'spso', 'ga', 'de'])
def test_comparison_algorithms_are_chosen_by_name(algorithm):
    result = plan(TARGET, algorithm=algorithm, seed=0, max_iterations=60)
    assert result.algorithm == algorithm
    direct = ALGORITHMS[algorithm](Objective(paper_arm(), Goal(PAPER_TARGET), np.zeros(5)),
                                   max_iter=60, seed=0)
    assert result.joint_goal[:4].tobytes() == direct.x.tobytes()
    assert result.iterations == direct.nit and result.evaluations == direct.nfev


def test_a_request_plans_as_the_same_keywords_do() -> None:
    request = PlanRequest(TARGET, [0.1] * 5, angular_velocity=0.5, seed=3, max_iterations=200)
    by_keywords = plan(TARGET, [0.1] * 5, angular_velocity=0.5, seed=3, max_iterations=200)
    by_request = plan(request)
    assert by_request.joint_goal.tobytes() == by_keywords.joint_goal.tobytes()
    assert (by_request.angular_velocity, by_request.motion) == (0.5, MotionProfile())
    # the earlier names of the keywords still work, and give the same plan
    old = plan(TARGET, [0.1] * 5, omega=0.5, seed=3, max_iter=200, profile=MotionProfile())
    assert old.joint_goal.tobytes() == by_request.joint_goal.tobytes()
    assert (old.omega, old.profile) == (old.angular_velocity, old.motion)


def test_a_request_is_checked_with_one_line_reasons() -> None:
    good = PlanRequest(TARGET)
    good.validate()
    for change, reason in [
            ({'algorithm': 'annealing'}, "unknown algorithm 'annealing'; choose from iepso"),
            ({'angular_velocity': 0.0}, 'angular_velocity must be finite and positive'),
            ({'goal': Goal(TARGET, tolerance=float('nan'))}, 'tolerance must be finite and '),
            ({'goal': Goal(TARGET, orientation=(0, 0, 0, 1))}, 'an orientation is for pose and '),
            ({'goal': Goal(TARGET, approach=(0, 0, 0))}, 'approach must be 3 finite numbers'),
            ({'max_planning_time': -1.0}, 'max_planning_time must be finite and positive'),
            ({'convergence_precision': -1e-9}, 'convergence_precision must be finite and not'),
            ({'population': 1}, 'population must be an integer of at least 2, got 1'),
            ({'max_iterations': 2.5}, 'max_iterations must be an integer of at least 1'),
            ({'seed': -3}, 'seed must be None, an integer >= 0 or a numpy Generator'),
            ({'optimizer_options': {'swarm': 4}}, 'iepso has no option swarm; it takes '),
            ({'algorithm': 'de', 'optimizer_options': {'swarms': 4}}, 'de has no option swarms'),
            ({'motion': MotionProfile('trapezoidal')}, 'acceleration')]:
        with pytest.raises(ValueError, match=reason):
            good.replace(**change).validate()
        with pytest.raises(ValueError, match=reason):
            plan(good.replace(**change))
    with pytest.raises(ValueError,
                       match="mode must be one of free, radial, approach, pose, got 'sideways'"):
        PlanRequest(Goal(TARGET, mode='sideways'))
    with pytest.raises(TypeError, match='give mode in the Goal, not beside it'):
        plan(Goal(TARGET), mode='radial')
    with pytest.raises(TypeError, match='unknown setting.* omeg; a plan takes algorithm'):
        plan(TARGET, omeg=1.0)
    with pytest.raises(TypeError, match='give angular_velocity or its old name omega'):
        plan(TARGET, omega=1.0, angular_velocity=1.0)
    with pytest.raises(TypeError, match='in the PlanRequest, not beside it'):
        plan(good, seed=1)


def test_bad_settings_raise():
    with pytest.raises(ValueError, match='unknown algorithm'):
        plan(TARGET, algorithm='annealing')
    with pytest.raises(ValueError):
        plan(TARGET, mode='sideways')
    with pytest.raises(ValueError):
        plan(TARGET, tolerance=-1)


class FakeClock:
    """A clock that advances by ``step`` seconds every time it is read (never the wall clock)."""

    def __init__(self, step: float) -> None:
        self.now, self.step, self.reads = 0.0, step, 0

    def __call__(self) -> float:
        self.now += self.step
        self.reads += 1
        return self.now


def calls_after(k: int) -> Callable[[], bool]:
    """Return a stop hook that is False for its first k calls, then True."""
    calls = itertools.count()
    return lambda: next(calls) >= k


def same_search(a, b) -> bool:
    return (a.joint_goal.tobytes() == b.joint_goal.tobytes() and a.iterations == b.iterations
            and a.evaluations == b.evaluations and a.efficiency.hex() == b.efficiency.hex()
            and a.history_efficiency.tobytes() == b.history_efficiency.tobytes())


@pytest.mark.parametrize('goal, algorithm, mode', [
    (TARGET, 'iepso', 'free'), (TARGET, 'iepso', 'radial'), (FAR, 'iepso', 'free'),
    (TARGET, 'pso', 'free'), (TARGET, 'de', 'radial')])
def test_a_deadline_and_a_stop_that_never_fire_change_nothing(goal, algorithm, mode):
    settings = {'algorithm': algorithm, 'mode': mode, 'seed': 1, 'max_iterations': 200}
    alone = plan(goal, **settings)
    asked = plan(goal, max_planning_time=1000.0, stop=lambda: False, **settings)
    assert same_search(alone, asked)                              # bit for bit
    assert asked.status is alone.status and asked.message == alone.message


def test_stop_from_the_start_cancels_after_the_first_iteration():
    result = plan(TARGET, seed=1, stop=lambda: True)
    assert result.status is PlanStatus.CANCELLED and not result.success
    assert result.message == 'planning stopped before the end'
    assert result.iterations == 1
    assert result.joint_goal is not None and np.isfinite(result.position_error_m)
    record = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    assert record['status'] == 'cancelled' and record['success'] is False


def test_stop_is_asked_after_every_iteration_and_every_polish_step():
    full = plan(FAR, seed=0)
    assert full.iterations > 20
    asks: list[int] = []
    plan(FAR, seed=0, stop=lambda: asks.append(1) is None and False)
    assert len(asks) > full.iterations                            # the polish steps ask too
    result = plan(FAR, seed=0, stop=calls_after(11))              # True at the twelfth ask
    assert result.status is PlanStatus.CANCELLED
    assert result.iterations < 12 < full.iterations


def test_deadline_times_out_with_the_best_answer_found(monkeypatch):
    clock = FakeClock(step=0.125)
    monkeypatch.setattr(planner, '_clock', clock)
    # read once to set the deadline, then at every ask (each iteration and polish step): past
    # 1.5 s at the twelfth
    result = plan(FAR, seed=0, max_planning_time=1.5)
    assert result.status is PlanStatus.TIMED_OUT and not result.success
    assert result.iterations < 12 and clock.reads == 13
    assert result.message == ('planning ran past max_planning_time 1.5 s; best position '
                              f'error {result.position_error_m:.3g} m')
    assert 1e-3 < result.position_error_m < 0.1 and '\n' not in result.message
    # the answer is the best of the twelve iterations (F evaluated once more), the one a run
    # interrupted there returns
    assert result.history_efficiency[-1] == result.history_efficiency.min()
    assert result.efficiency == pytest.approx(result.history_efficiency[-1], rel=1e-6)
    assert result.position_error_m == pytest.approx(result.history_error[-1], rel=1e-6)
    asks = itertools.count(1)
    direct = iepso(Objective(paper_arm(), Goal(np.array(FAR)), np.zeros(5)), seed=0,
                   interrupt=lambda: 'late' if next(asks) >= 12 else None)
    assert result.joint_goal[:4].tobytes() == direct.x.tobytes()
    assert (result.iterations, result.evaluations) == (direct.nit, direct.nfev)
    record = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    assert record['status'] == 'timed_out' and record['success'] is False
    assert record['joint_goal'] == result.joint_goal.tolist()


@pytest.mark.parametrize('algorithm', ['pso', 'ga'])
def test_a_comparison_algorithm_times_out_too(monkeypatch, algorithm):
    monkeypatch.setattr(planner, '_clock', FakeClock(step=1.0))
    result = plan(TARGET, algorithm=algorithm, seed=0, max_planning_time=3.0)
    assert result.status is PlanStatus.TIMED_OUT and result.iterations == 3
    assert result.message.startswith('planning ran past max_planning_time 3 s; best position')
    assert result.efficiency == pytest.approx(result.history_efficiency.min(), rel=1e-6)


def test_stop_is_asked_before_the_clock(monkeypatch):
    monkeypatch.setattr(planner, '_clock', FakeClock(step=1.0))
    result = plan(TARGET, algorithm='de', seed=0, max_planning_time=2.0, stop=calls_after(1))
    assert result.status is PlanStatus.CANCELLED and result.iterations == 2


@pytest.mark.parametrize('limit', [0, -1.0, float('nan'), float('inf')])
def test_a_bad_planning_time_raises(limit):
    with pytest.raises(ValueError, match='max_planning_time'):
        plan(TARGET, max_planning_time=limit)


def test_a_stop_that_cannot_be_called_raises():
    with pytest.raises(ValueError, match='stop'):
        plan(TARGET, stop=True)


def test_a_start_gives_every_joint_or_the_planned_ones() -> None:
    full = plan(TARGET, [0.1, 0.2, 0.0, 0.0, 0.0], seed=0)
    planned = plan(TARGET, [0.1, 0.2, 0.0, 0.0], seed=0)
    np.testing.assert_array_equal(full.joint_goal, planned.joint_goal)
    for start in ([0.1], [0.0] * 6):
        result = plan(TARGET, start, seed=0)
        assert result.status is PlanStatus.REJECTED
        assert f'a start needs 5 joint angles (or the 4 planned ones), got {len(start)}' in (
            result.message)


def test_radial_puts_the_tool_axis_on_the_goal_ray_pointing_outward() -> None:
    result = plan(TARGET, mode='radial', seed=0)
    assert result.success and result.axis_error_rad <= 1e-9
    p, u = paper_arm().tool(result.joint_goal[None, :])
    ray = PAPER_TARGET / np.linalg.norm(PAPER_TARGET)
    assert u[0] @ ray == pytest.approx(1.0, abs=1e-12)
    assert 'from the goal ray' in result.message


def test_a_mirrored_pose_is_an_axis_error_of_twice_the_goal_angle() -> None:
    # the old cone reading accepted the tool tilted by eps on the far side of the base z axis
    arm, goal = paper_arm(), np.array([0.12, 0.05, 0.2])
    eps = radial_angle(goal)
    mirrored = _solutions(arm, goal, np.array([-eps]))[0, 1]        # base facing, -eps
    assert arm.within_limits(np.append(mirrored, 0.0))
    obj = Objective(arm, Goal(goal, mode='radial'), np.zeros(5))
    p, u = obj.tool(mirrored[None, :])
    assert np.linalg.norm(p[0] - goal) < 1e-12                      # the goal is reached ...
    assert obj.axis_angle(u)[0] == pytest.approx(2 * eps)           # ... but not along the ray
    assert obj(mirrored[None, :]).error[0] > 0.01
    inward = obj.axis_angle(-goal[None, :] / np.linalg.norm(goal))
    assert inward[0] == pytest.approx(np.pi)                        # pointing at the base: pi
    result = plan(goal, mode='radial', seed=0)
    assert result.success and result.axis_error_rad < 1e-9


def test_a_goal_without_a_radial_pose_is_not_reached() -> None:
    cases = draw_cases(paper_arm(), 3, mode=Mode.RADIAL, random_starts=True, seed=5,
                       only='no-solution')
    for case in cases:
        result = plan(case.goal, case.start, mode='radial', seed=case.seed)
        assert result.status is PlanStatus.NOT_REACHED, case.goal
        assert 'goal ray' in result.message
        assert result.axis_error_rad > 1e-6 or result.position_error_m > 1e-6


@pytest.mark.parametrize('mode', ['free', 'radial'])
def test_optima_on_a_joint_limit_are_found(mode: str) -> None:
    arm = paper_arm()
    for case in draw_cases(arm, 3, mode=Mode(mode), random_starts=True, seed=8,
                           only='limit-optima'):
        result = plan(case.goal, case.start, mode=mode, seed=case.seed)
        assert result.success
        assert result.motion_time_s == pytest.approx(case.exact_time, rel=1e-6)


def test_equal_motion_times_go_to_the_least_joint_travel() -> None:
    arm = paper_arm()
    cases = draw_cases(arm, 12, mode=Mode.FREE, random_starts=False, seed=77)
    tied = [c for c in cases if np.argmax(np.abs(c.exact.joint_goal - c.start[:4])) == 0]
    assert len(tied) >= 3                 # the base joint is slowest: a whole arc ties
    for case in tied:
        result = plan(case.goal, case.start, seed=case.seed)
        travel = np.abs(result.joint_goal[:4] - case.start[:4]).sum()
        least = np.abs(case.exact.joint_goal - case.start[:4]).sum()
        assert result.motion_time_s == pytest.approx(case.exact_time, rel=1e-9)
        assert travel == pytest.approx(least, abs=1e-5)


def test_a_bad_axis_tolerance_raises() -> None:
    with pytest.raises(ValueError, match='axis_tolerance'):
        plan(TARGET, mode='radial', axis_tolerance=0.0)


def test_residuals_below_rounding_are_written_as_zero() -> None:
    assert describe_residual(1.09e-15, 'm') == '0 m'
    assert describe_residual(2.5e-12, 'rad') == '2.5e-12 rad'
    assert describe_residual(3.14159e-7, 'm') == '3.14e-07 m'
    result = plan([0.151171, 0.19162, 0.172124], seed=0)
    assert result.position_error_m < 1e-12 and result.message.endswith('error 0 m')


def test_a_stopped_panda_plan_ends_at_once_even_inside_the_multistart() -> None:
    # the multi-start polishes 77 candidates for about 25 ms (numpy core) without an iteration
    # of its own: the stop is asked after every polish step, so the plan ends within one
    from trajplan_ros import ArmModel
    from trajplan_ros.tools.bench.cases import PUBLISHED

    panda = PUBLISHED['panda']
    arm = ArmModel.from_urdf(panda.urdf, panda.base_link, panda.tip_link)
    rng = np.random.default_rng(4)
    q = rng.uniform(np.maximum(arm.lower, -3), np.minimum(arm.upper, 3), (2, arm.n_joints))
    goal, start = arm.tool(q[:1])[0][0], q[1]
    polls: list[float] = []
    whole = plan(goal, start, arm=arm, angular_velocity=1.0, seed=0,
                 stop=lambda: polls.append(0) or False)
    assert whole.success and len(polls) > 10                  # polls inside the multi-start
    for first in (2, len(polls) // 2):
        asked: list[float] = []

        def stop() -> bool:
            asked.append(time.perf_counter())
            return len(asked) >= first

        result = plan(goal, start, arm=arm, angular_velocity=1.0, seed=0, stop=stop)
        ended = time.perf_counter()
        assert result.status is PlanStatus.CANCELLED
        assert len(asked) <= first + 3                        # the stages after it ask once each
        assert ended - asked[first - 1] < 0.05                # the bound, with room
