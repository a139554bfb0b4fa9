# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The servo trajectory: fixed angular velocity, controller-ready timing."""
import tracemalloc

import numpy as np
import pytest

from trajplan_ros.motion.motion_profile import Timing
from trajplan_ros.motion.time_law import JERK_LIMITED, SERVO, TimeLaw, TRAPEZOIDAL
from trajplan_ros.motion.trajectory import motion_states, motion_trajectory, servo_trajectory
from trajplan_ros.planning import trajectory_points

START = np.array([0.0, 0.5, -0.2, 0.1, 0.0])
GOAL = np.array([0.9, 0.1, 0.3, 0.1, 0.0])
OMEGA = 0.2


def test_timing_is_controller_ready():
    traj = servo_trajectory(START, GOAL, OMEGA, sample_period=0.1)
    assert traj.times[0] > 0
    assert np.all(np.diff(traj.times) > 0)
    assert traj.duration == pytest.approx(0.9 / OMEGA)
    np.testing.assert_array_equal(traj.positions[-1], GOAL)
    assert traj.velocities is None and traj.accelerations is None      # positions only
    np.testing.assert_array_equal(np.array(traj.nanoseconds) / 1e9, traj.times)   # whole ns


def test_every_joint_turns_at_omega_until_it_arrives():
    traj = servo_trajectory(START, GOAL, OMEGA, sample_period=0.05)
    arrive = np.abs(GOAL - START) / OMEGA
    expected = START + np.sign(GOAL - START) * OMEGA * np.minimum(traj.times[:, None], arrive)
    np.testing.assert_allclose(traj.positions, expected, atol=1e-12)
    segments = np.diff(np.vstack((START, traj.positions)), axis=0)
    velocity = segments / np.diff(traj.times, prepend=0.0)[:, None]
    moving = traj.times[:, None] <= arrive + 1e-9
    np.testing.assert_allclose(np.abs(velocity), np.where(moving, OMEGA, 0.0), atol=1e-12)
    for t in arrive[arrive > 0]:
        assert np.min(np.abs(traj.times - t)) < 1e-9      # corners are sampled exactly


def test_at_time_interpolates_from_the_start():
    traj = servo_trajectory(START, GOAL, OMEGA)
    after_one_second = START + np.sign(GOAL - START) * np.minimum(OMEGA, np.abs(GOAL - START))
    np.testing.assert_allclose(traj.at_time(np.array([0.0, 1.0, 100.0]))[0],
                               [START, after_one_second, GOAL], atol=1e-12)


@pytest.mark.parametrize('kind', [SERVO, TRAPEZOIDAL, JERK_LIMITED])
@pytest.mark.parametrize('timing', list(Timing))
def test_at_time_is_the_motion_for_every_law(kind: int, timing: Timing) -> None:
    # between points the polynomial the controller fits is the law's own motion: the same
    # positions, velocities and accelerations as the profile's closed form, to rounding
    rng = np.random.default_rng(17 + kind)
    for _ in range(40):
        n = 4
        law = TimeLaw(kind, 10 ** rng.uniform(-1, 1, n),
                      10 ** rng.uniform(-1, 1.5, n) if kind != SERVO else np.full(n, np.inf),
                      10 ** rng.uniform(0, 2.5, n) if kind == JERK_LIMITED else np.full(n, np.inf))
        start, goal = rng.uniform(-2, 2, n), rng.uniform(-2, 2, n)
        traj = motion_trajectory(start, goal, law, timing, sample_period=0.1)
        t = np.concatenate((rng.uniform(0, traj.duration, 200), traj.times, [traj.duration + 1]))
        q, v, a = traj.at_time(t)
        exact_q, exact_v, exact_a, _ = motion_states(start, goal, law, timing, t)
        assert np.abs(q - exact_q).max() <= 1e-8
        assert np.abs(v - exact_v).max() <= 1e-6 * law.velocity.max()
        if kind != SERVO:
            assert np.abs(a - exact_a).max() <= 1e-6 * law.acceleration.max()
        np.testing.assert_array_equal(q[-1], goal)
        assert not v[-1].any() and not a[-1].any()


def test_no_motion_gives_one_resting_point():
    traj = servo_trajectory(START, START, OMEGA, sample_period=0.2)
    assert traj.times.tolist() == [0.2]
    np.testing.assert_array_equal(traj.positions, [START])


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


def points(start, goal, omega, sample_period):
    """Return (built, counted): the number of points of the trajectory, both ways."""
    built = servo_trajectory(start, goal, omega, sample_period=sample_period).times.size
    return built, trajectory_points(start, goal, omega, sample_period)


def random_case(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Return a start, goal, omega and sample period, edge cases often, < 3e4 points."""
    n = int(rng.integers(1, 8))
    omega = float(rng.choice([1.0, 0.5, 0.2, rng.uniform(0.01, 3.0)]))
    period = float(rng.choice([0.1, 0.3, 1 / 3, 0.05, 1e-3, 1e-4, 1e-5, 2e-6, 1.5e-6, 1e-6,
                               9.99e-7, 5e-7, 1e-7, 3e-8, rng.uniform(1e-4, 1.0)]))
    start = np.zeros(n) if rng.random() < 0.4 else rng.uniform(-3, 3, n)  # 0: exact arrivals
    reach = min(6.0, 2e4 * period * omega)
    steps = rng.integers(0, max(1, int(reach / omega / period)), n)
    sign = rng.choice([-1.0, 1.0], n)
    kind = rng.integers(0, 5)
    if kind == 0:                                        # anywhere
        delta = rng.uniform(-reach, reach, n)
    elif kind == 1:                                      # arrivals on grid points
        delta = sign * steps * period * omega
    elif kind == 2:                                      # no motion, or within a microsecond
        delta = sign * rng.choice([0.0, 1e-12, 1e-7 * omega, 1e-6 * omega, 2e-6 * omega], n)
    elif kind == 3:                                      # arrivals a microsecond off grid points
        off = rng.choice([-1e-6, -5e-7, 0.0, 5e-7, 1e-6, 1.0000001e-6], n)
        delta = sign * (steps * period + off) * omega
    else:                                                # some joints still
        delta = np.where(rng.random(n) < 0.5, 0.0, rng.uniform(-reach, reach, n))
    return start, start + delta, omega, period


def test_points_are_counted_as_built_on_thousands_of_cases():
    rng = np.random.default_rng(7)
    for case in range(3000):
        start, goal, omega, period = random_case(rng)
        built, counted = points(start, goal, omega, period)
        assert counted == built, (case, start.tolist(), goal.tolist(), omega, period)


@pytest.mark.parametrize('goal, omega, period, expected', [
    (START, OMEGA, 0.1, 1),                                   # no motion: one resting point
    (START + 1e-7, OMEGA, 0.1, 1),                            # within a microsecond
    (START + np.array([0.5, 0, 0, 0, 0]), 0.5, 0.25, 4),      # 0.25 0.5 0.75 1.0: on the grid
    (START + np.array([0.5, 0.25, 0, 0, 0]), 0.5, 0.3, 5),    # 0.3 0.5 0.6 0.9 1.0
    (START + np.array([0.5, 0.25 + 2e-7, 0, 0, 0]), 0.5, 0.25, 4),    # arrival merges in
    (START + np.array([1.0, 0, 0, 0, 0]), 1.0, 1e-4, 10000),  # a tiny period
    (START + np.array([1.0, 0, 0, 0, 0]), 1.0, 1e-7, 1),      # below the microsecond: merged
])
def test_edge_cases(goal, omega, period, expected):
    assert points(START, goal, omega, period) == (expected, expected)


def test_counting_needs_no_arrays_of_the_trajectorys_length():
    # a 1e4 s motion sampled every 2^-10 s (exact grid times): 10,240,000 grid points, which
    # the arrivals at 2000.5 s and 4000 s land on, plus one at 0.6 s; the 2 ns one is no point
    start = np.zeros(5)
    goal = np.array([5000.0, 1000.25, -2000.0, 0.3, 1e-9])
    tracemalloc.start()
    try:
        counted = trajectory_points(start, goal, 0.5, 2.0 ** -10)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert counted == 10_240_001
    assert peak < 100_000                                 # bytes; the times alone take 80 MB
    assert trajectory_points(start, goal, 0.5, 0.5) == 20_000 + 1


def test_counting_checks_its_arguments_like_the_trajectory():
    for args in ((START, GOAL[:3], OMEGA, 0.1), (START, GOAL, -1.0, 0.1),
                 (START, GOAL, OMEGA, 0.0), (START, GOAL, np.nan, 0.1)):
        with pytest.raises(ValueError):
            trajectory_points(*args)


def test_short_segments_are_never_faster_than_omega_but_for_rounding():
    # an arrival a microsecond and a bit before a grid point makes a segment that short: the
    # positions' own rounding (an ulp of ~3 rad) is then the only excess over omega * dt
    start = np.array([2.942, 0.0])
    goal = start + OMEGA * np.array([3.0 - 1.05e-6, 3.2])
    traj = servo_trajectory(start, goal, OMEGA, sample_period=0.1)
    dt = np.diff(traj.times, prepend=0.0)[:, None]
    step = np.abs(np.diff(np.vstack((start, traj.positions)), axis=0))
    assert dt.min() < 2e-6                                        # the short segment is there
    assert np.all(step <= OMEGA * dt + 4 * np.spacing(np.abs(traj.positions)))
