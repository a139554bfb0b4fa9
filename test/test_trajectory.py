# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The servo trajectory: fixed angular velocity, controller-ready timing."""
import numpy as np
import pytest

from trajplan_ros.planning.trajectory import servo_trajectory

START = np.array([0.0, 0.5, -0.2, 0.1, 0.0])
GOAL = np.array([0.9, 0.1, 0.3, 0.1, 0.0])
OMEGA = 0.2


def test_timing_is_controller_ready():
    traj = servo_trajectory(START, GOAL, OMEGA, sample_period=0.1)
    assert traj.times[0] > 0
    assert np.all(np.diff(traj.times) > 0)
    assert traj.duration == pytest.approx(0.9 / OMEGA)
    np.testing.assert_array_equal(traj.positions[-1], GOAL)
    np.testing.assert_array_equal(traj.velocities[-1], 0.0)


def test_every_joint_turns_at_omega_until_it_arrives():
    traj = servo_trajectory(START, GOAL, OMEGA, sample_period=0.05)
    arrive = np.abs(GOAL - START) / OMEGA
    expected = START + np.sign(GOAL - START) * OMEGA * np.minimum(traj.times[:, None], arrive)
    np.testing.assert_allclose(traj.positions, expected, atol=1e-12)
    moving = traj.times[:, None] < arrive - 1e-9
    np.testing.assert_allclose(np.abs(traj.velocities), np.where(moving, OMEGA, 0.0))
    for t in arrive[arrive > 0]:
        assert np.min(np.abs(traj.times - t)) < 1e-9      # corners are sampled exactly


def test_sample_interpolates_from_the_start():
    traj = servo_trajectory(START, GOAL, OMEGA)
    after_one_second = START + np.sign(GOAL - START) * np.minimum(OMEGA, np.abs(GOAL - START))
    np.testing.assert_allclose(traj.sample(np.array([0.0, 1.0, 100.0])),
                               [START, after_one_second, GOAL], atol=1e-12)


def test_no_motion_gives_one_resting_point():
    traj = servo_trajectory(START, START, OMEGA, sample_period=0.2)
    assert traj.times.tolist() == [0.2]
    np.testing.assert_array_equal(traj.velocities, 0.0)


def test_a_joint_that_barely_moves_adds_no_point_at_the_start():
    # an optimiser's answer may leave a joint 1e-17 rad off its start: that arrival is not a point
    goal = GOAL + np.array([0.0, 0.0, 0.0, 1e-17, 1e-15])
    traj = servo_trajectory(START, goal, OMEGA)
    assert traj.times[0] >= 1e-6 and np.all(np.diff(traj.times) > 1e-6)
    np.testing.assert_array_equal(traj.positions[-1], goal)
    tiny = servo_trajectory(START, START + 1e-12, OMEGA, sample_period=0.2)
    assert tiny.times.tolist() == [0.2]
    np.testing.assert_array_equal(tiny.positions[-1], START + 1e-12)


def test_bad_arguments_raise():
    with pytest.raises(ValueError):
        servo_trajectory(START, GOAL[:3], OMEGA)
    with pytest.raises(ValueError):
        servo_trajectory(START, GOAL, -1.0)
