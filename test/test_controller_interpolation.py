# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The servo message under joint_trajectory_controller's interpolation: never above a joint's speed.

``controller_interpolation`` reproduces how the controller (ros2_controllers, jazzy) samples a
JointTrajectory. The first tests check that reproduction on messages whose motion is known by
hand; the others plan goals on the paper arm and on the SO-101 URDF and check that what the
controller commands from each plan's message never turns a joint faster than its speed, starts
at the plan's start, ends exactly at its joint goal and then rests.
"""
from __future__ import annotations

import math
from typing import Any

from controller_interpolation import (BEFORE_FIRST_POINT, ControllerTrajectory, CUBIC,
                                      JTC_COMMIT, LINEAR, message_dict, NONE, QUINTIC,
                                      sample, Segment, validate_trajectory_msg)
import numpy as np
import pytest
from trajplan_ros import ArmModel, paper_arm, plan
from trajplan_ros.ros.messages import trajectory_msg
from trajplan_ros.tools.bench.cases import PUBLISHED

S = 1_000_000_000           # ns per second
MS = 1_000_000              # ns per millisecond
#: How far above a joint's speed the commanded velocity may be: rounding only.
RELATIVE = 1e-9


def message(times: list[float], positions: list[list[float]],
            velocities: list[list[float]] | None = None,
            accelerations: list[list[float]] | None = None) -> dict[str, Any]:
    """Return a message in the JSON form, ``joint1..`` named, fields as given."""
    points = [{'time_from_start': t, 'positions': list(q),
               'velocities': list(velocities[k]) if velocities else [],
               'accelerations': list(accelerations[k]) if accelerations else []}
              for k, (t, q) in enumerate(zip(times, positions))]
    return {'joint_names': [f'joint{i + 1}' for i in range(len(positions[0]))],
            'points': points}


# --- the reproduction, on motions known by hand -------------------------------------------------

def test_it_names_the_controller_source_it_reproduces() -> None:
    assert len(JTC_COMMIT) == 40 and int(JTC_COMMIT, 16) >= 0


def test_positions_only_give_piecewise_linear_motion_then_rest() -> None:
    msg = message([1.0, 3.0, 3.5], [[1.0, -2.0], [2.0, -2.0], [0.0, 1.0]])
    traj = ControllerTrajectory(msg, {'positions': [0.5, 0.0], 'velocities': [0.3, 0.0]})
    assert [s.kind for s in traj.segments()] == [LINEAR] * 3
    times = np.array([0, S // 2, S, 2 * S, 3 * S, 3 * S + S // 4, 7 * S // 2, 9 * S])
    out = traj.sample(times)
    assert out.valid.all()
    assert out.segment.tolist() == [BEFORE_FIRST_POINT, BEFORE_FIRST_POINT, 0, 0, 1, 1, 2, 2]
    expected_v = [[0.5, -2.0], [0.5, -2.0], [0.5, 0.0], [0.5, 0.0], [-4.0, 6.0], [-4.0, 6.0],
                  [0.0, 0.0], [0.0, 0.0]]
    np.testing.assert_allclose(out.velocities, expected_v, rtol=1e-15)
    expected_q = [[0.5, 0.0], [0.75, -1.0], [1.0, -2.0], [1.5, -2.0], [2.0, -2.0], [1.0, -0.5],
                  [0.0, 1.0], [0.0, 1.0]]
    np.testing.assert_allclose(out.positions, expected_q, rtol=1e-15, atol=1e-15)
    np.testing.assert_array_equal(out.positions[[0, 2, 4, 6]], [[0.5, 0.0], *msg_positions(msg)])
    np.testing.assert_array_equal(out.accelerations, 0.0)


def msg_positions(msg: dict[str, Any]) -> list[list[float]]:
    """Return each point's positions."""
    return [p['positions'] for p in msg['points']]


def test_points_with_velocities_give_cubics_through_their_ends() -> None:
    msg = message([2.0, 3.0], [[1.0], [1.5]], velocities=[[0.8], [0.0]])
    traj = ControllerTrajectory(msg, {'positions': [0.0], 'velocities': [0.25]})
    first, second = traj.segments()
    assert (first.kind, second.kind) == (CUBIC, CUBIC)
    for segment, (q0, v0, q1, v1) in zip((first, second), ((0.0, 0.25, 1.0, 0.8),
                                                           (1.0, 0.8, 1.5, 0.0))):
        q, v, _ = segment.evaluate(np.array([0.0, segment.duration]))
        np.testing.assert_allclose(q.ravel(), [q0, q1], rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(v.ravel(), [v0, v1], rtol=1e-14, atol=1e-15)
    out = traj.sample([0, 2 * S, 3 * S])         # a point's time starts its segment: exact
    np.testing.assert_array_equal(out.positions.ravel(), [0.0, 1.0, 1.5])
    np.testing.assert_array_equal(out.velocities.ravel(), [0.25, 0.8, 0.0])


def test_one_resting_point_after_rest_is_a_cubic_that_peaks_at_one_and_a_half_the_average(
        ) -> None:
    # the overshoot the servo message avoids by leaving velocities out
    msg = message([2.0], [[1.0, -0.5]], velocities=[[0.0, 0.0]])
    traj = ControllerTrajectory(msg, {'positions': [0.0, 0.0]})     # the state has no velocity
    (segment,) = traj.segments()
    assert segment.kind == CUBIC
    out = traj.sample(np.arange(0, 2 * S + 1, MS))
    average = np.array([0.5, -0.25])
    np.testing.assert_allclose(out.velocities[1000], 1.5 * average, rtol=1e-12)
    np.testing.assert_allclose(np.max(np.abs(out.velocities), axis=0), 1.5 * np.abs(average),
                               rtol=1e-12)
    np.testing.assert_allclose(segment.max_abs_jerk(), 12 * np.abs([1.0, -0.5]) / 8, rtol=1e-12)
    np.testing.assert_array_equal(out.positions[-1], [1.0, -0.5])
    np.testing.assert_array_equal(out.velocities[-1], [0.0, 0.0])


def test_points_with_velocities_and_accelerations_give_quintics() -> None:
    # rest to rest over d = 1 in T = 2 s: peak velocity 15 d / (8 T), peak jerk 60 d / T^3
    msg = message([2.0], [[1.0]], velocities=[[0.0]], accelerations=[[0.0]])
    traj = ControllerTrajectory(msg, {'positions': [0.0]})
    (segment,) = traj.segments()
    assert segment.kind == QUINTIC
    out = traj.sample(np.arange(0, 2 * S + 1, MS))
    assert np.max(out.velocities) == pytest.approx(15 / 16, rel=1e-12)
    assert np.max(np.abs(out.accelerations)) == pytest.approx(10 / math.sqrt(3) / 4, rel=1e-6)
    assert segment.max_abs_jerk()[0] == pytest.approx(60 / 8, rel=1e-12)
    u = np.arange(0, 2 * S + 1, MS) / (2 * S)
    jerk = np.gradient(out.accelerations[:, 0], 1e-3)[1:-1]
    np.testing.assert_allclose(jerk, 60 / 8 * (1 - 6 * u + 6 * u ** 2)[1:-1], atol=1e-5)
    msg = message([2.0], [[1.0]], velocities=[[0.0]], accelerations=[[0.3]])
    (segment,) = ControllerTrajectory(msg, {'positions': [0.0]}).segments()
    q, v, a = segment.evaluate(np.array([0.0, 2.0]))
    np.testing.assert_allclose(np.hstack((q, v, a)), [[0, 0, 0], [1, 0, 0.3]], atol=1e-14)


def test_the_largest_jerk_of_a_segment_is_its_largest_on_a_dense_grid() -> None:
    rng = np.random.default_rng(3)
    q, v, a = (rng.uniform(-1, 1, (6, 4)) for _ in range(3))
    v[-1] = 0.0
    msg = message([0.3, 0.5, 1.2, 1.25, 2.0, 3.0], q.tolist(), velocities=v.tolist(),
                  accelerations=a.tolist())
    for segment in ControllerTrajectory(msg, {'positions': [0.0] * 4}).segments():
        s = np.linspace(0.0, segment.duration, 20001)[:, None]
        c = segment.coefficients.T[:, None, :]
        jerk = 6 * c[3] + 24 * c[4] * s + 60 * c[5] * s ** 2
        np.testing.assert_allclose(segment.max_abs_jerk(), np.max(np.abs(jerk), axis=0),
                                   rtol=1e-6)
    # jerk 60 s (s - 1): zero at both ends, -15 at s = 0.5
    vertex = Segment(0, 0, S, QUINTIC, np.array([[0.0, 0.0, 0.0, 0.0, -2.5, 1.0]]))
    np.testing.assert_allclose(vertex.max_abs_jerk(), [15.0], rtol=1e-15)


def test_the_first_segment_takes_the_states_derivatives_or_zeros() -> None:
    with_v = message([1.0], [[1.0]], velocities=[[0.0]])
    moving = ControllerTrajectory(with_v, {'positions': [0.0], 'velocities': [2.0]})
    assert moving.sample([0]).velocities[0, 0] == 2.0
    assert sample(with_v, {'positions': [0.0]}, [0]).velocities[0, 0] == 0.0
    # a state with velocities before a point without them: linear
    plain = ControllerTrajectory(message([1.0], [[1.0]]),
                                 {'positions': [0.0], 'velocities': [2.0]})
    assert plain.segments()[0].kind == LINEAR
    assert plain.sample([0]).velocities[0, 0] == 1.0


def test_accelerations_without_velocities_command_zeros() -> None:
    msg = message([1.0, 2.0], [[1.0], [2.0]], accelerations=[[0.0], [0.0]])
    traj = ControllerTrajectory(msg, {'positions': [0.5]})
    assert [s.kind for s in traj.segments()] == [NONE, NONE]
    out = traj.sample([S // 2, 3 * S // 2, 2 * S])
    np.testing.assert_array_equal(out.positions.ravel(), [0.0, 0.0, 2.0])


def test_a_stamp_starts_the_trajectory_and_the_state_fills_the_wait() -> None:
    msg = message([1.0], [[1.0]])
    traj = ControllerTrajectory(msg, {'positions': [0.0]}, state_time_ns=5 * S,
                                header_stamp_ns=7 * S)
    out = traj.sample([4 * S, 5 * S, 6 * S, 8 * S])
    assert out.valid.tolist() == [False, True, True, True]
    np.testing.assert_allclose(out.positions[1:, 0], [0.0, 1 / 3, 1.0], rtol=1e-15)
    # a zero stamp starts it at the first sample: here the state's time
    late = ControllerTrajectory(msg, {'positions': [0.0]}, state_time_ns=5 * S)
    np.testing.assert_allclose(late.sample([5 * S + S // 2]).positions[0], [0.5], rtol=1e-15)


def test_points_without_positions_are_integrated() -> None:
    # allow_integration_in_goal_trajectories: positions from the trapezoid of the velocities
    msg = {'joint_names': ['joint1'],
           'points': [{'time_from_start': 1.0, 'velocities': [1.0], 'accelerations': [0.0]},
                      {'time_from_start': 2.0, 'velocities': [0.0], 'accelerations': [0.0]}]}
    assert validate_trajectory_msg(msg) is not None
    assert validate_trajectory_msg(msg, allow_integration_in_goal_trajectories=True) is None
    traj = ControllerTrajectory(msg, {'positions': [0.0]})
    out = traj.sample([0, 1 * S, 2 * S, 3 * S])         # the controller's first sample: t = 0
    np.testing.assert_allclose(out.positions.ravel(), [0.0, 0.5, 1.0, 1.0], rtol=1e-15)


def test_a_continuous_joints_state_is_moved_next_to_the_first_point() -> None:
    msg = message([1.0], [[-3.0, -3.0]])
    traj = ControllerTrajectory(msg, {'positions': [3.0, 3.0]}, angle_wraparound=[True, False])
    start = traj.sample([0]).positions[0]
    np.testing.assert_allclose(start, [-3.0 - (2 * math.pi - 6.0), 3.0], rtol=1e-15)


def test_validation_reproduces_the_controllers_reasons() -> None:
    good = message([0.5, 1.0], [[0.0, 1.0], [1.0, 1.0]], velocities=[[1.0, 0.0], [0.0, 0.0]])
    assert validate_trajectory_msg(good) is None
    assert validate_trajectory_msg(good, joints=['joint1']) is not None
    assert 'joint2' in validate_trajectory_msg(good, joints=['joint1', 'joint3'])
    same_time = message([0.5, 0.5], [[0.0, 1.0], [1.0, 1.0]])
    assert 'strictly increasing' in validate_trajectory_msg(same_time)
    moving_end = message([0.5, 1.0], [[0.0, 1.0], [1.0, 1.0]],
                         velocities=[[1.0, 0.0], [0.0, 1e-6]])
    assert 'not zero' in validate_trajectory_msg(moving_end)
    assert validate_trajectory_msg(moving_end, allow_nonzero_velocity_at_trajectory_end=True) \
        is None
    short = message([0.5, 1.0], [[0.0, 1.0], [1.0]])
    assert 'positions (1) at point #1' in validate_trajectory_msg(short)
    no_positions = message([0.5], [[]])
    no_positions['joint_names'] = ['joint1']
    assert 'positions (0)' in validate_trajectory_msg(no_positions)
    good['points'][0]['effort'] = [0.0, 0.0]
    assert 'effort' in validate_trajectory_msg(good)
    assert validate_trajectory_msg({'joint_names': ['joint1'], 'points': []}) is not None


# --- plans: the controller's commanded velocity never exceeds a joint's speed -------------------

def so101() -> ArmModel:
    """Return the SO-101 arm of example-robot-data (URDF velocity limits 10 rad/s)."""
    arm = PUBLISHED['so101']
    return ArmModel.from_urdf(arm.urdf, arm.base_link, arm.tip_link)


#: (arm factory, omega rad/s, goals, seed); on the SO-101, omega 20 is above its URDF limit.
CASES = {
    'paper-0.2': (paper_arm, 0.2, 30, 11),
    'paper-1.0': (paper_arm, 1.0, 30, 12),
    'so101-1.0': (so101, 1.0, 15, 13),
    'so101-20': (so101, 20.0, 15, 14),
}


def check_under_the_controller(arm: ArmModel, result: Any, omega: float) -> float:
    """Check one plan's message under the controller; return its largest velocity / speed."""
    traj = result.trajectory(arm, sample_period=0.1)
    msg = traj.to_dict()
    assert validate_trajectory_msg(msg, joints=arm.joint_names) is None
    np.testing.assert_array_equal(traj.start, result.start)
    speed = arm.speeds(omega)
    controller = ControllerTrajectory(msg, {'positions': traj.start.tolist(),
                                            'velocities': [0.0] * arm.n_joints})
    segments = controller.segments()
    assert {s.kind for s in segments} == {LINEAR}
    # linear: one velocity per segment, checked exactly
    exact = max(float(np.max(np.abs(s.coefficients[:, 1]) / speed)) for s in segments)
    ends = np.array([[s.t0_ns, s.t0_ns + 1, s.t1_ns - 1] for s in segments]).ravel()
    grid = np.arange(0, controller.end_ns + S // 2, MS)
    times = np.unique(np.concatenate((grid, ends, [controller.end_ns])))
    out = controller.sample(times)
    assert out.valid.all()
    sampled = float(np.max(np.abs(out.velocities) / speed))
    assert max(exact, sampled) <= 1 + RELATIVE, (exact, sampled)
    np.testing.assert_array_equal(out.positions[0], result.start)
    after = times >= controller.end_ns
    np.testing.assert_array_equal(out.positions[after], np.broadcast_to(
        result.joint_goal, out.positions[after].shape))
    np.testing.assert_array_equal(out.velocities[after], 0.0)
    np.testing.assert_array_equal(out.accelerations[after], 0.0)
    return max(exact, sampled)


@pytest.mark.parametrize('case', sorted(CASES))
def test_the_controller_never_turns_a_joint_faster_than_its_speed(case: str) -> None:
    make, omega, goals, seed = CASES[case]
    arm = make()
    rng = np.random.default_rng(seed)
    q = rng.uniform(arm.lower, arm.upper, (goals, arm.n_joints))
    starts = rng.uniform(arm.lower, arm.upper, (goals, arm.n_joints))
    succeeded, ratios = 0, []
    for k in range(goals):
        goal = arm.tool(q[k:k + 1])[0][0]
        result = plan(goal, starts[k] if k % 2 else None, arm=arm, angular_velocity=omega, seed=k)
        if not result.success:
            continue
        succeeded += 1
        ratios.append(check_under_the_controller(arm, result, omega))
    assert succeeded >= 0.8 * goals, f'{succeeded} of {goals} plans succeeded'
    print(f'{case}: {succeeded}/{goals} plans, largest velocity / speed {max(ratios)!r}')


def test_the_published_message_is_the_one_checked() -> None:
    arm = paper_arm()
    goal = arm.tool(np.array([[0.4, 0.6, -0.9, 0.3, 0.2]]))[0][0]
    result = plan(goal, [0.1, -0.2, 0.3, 0.0, 0.5], arm=arm, angular_velocity=0.2, seed=0)
    assert result.success
    traj = result.trajectory(arm, sample_period=0.1)
    msg = trajectory_msg(traj)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (0, 0)      # start now
    assert message_dict(msg) == traj.to_dict()
    assert all(not p['velocities'] and not p['accelerations'] for p in message_dict(msg)['points'])
