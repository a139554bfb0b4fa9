# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The joints' time laws (eq. 10 and the rest-to-rest profiles) as the kernels compute them.

Ruckig (PyPI ``ruckig``, a test dependency) is the independent check of the profiles' durations.
"""
from __future__ import annotations

import numpy as np
import pytest
import ruckig
from trajplan_ros import ArmModel, paper_arm
from trajplan_ros.motion.time_law import (JERK_LIMITED, joint_reach, joint_time, motion_times,
                                          SERVO, servo_law, tie_scales, TimeLaw, TRAPEZOIDAL)
from trajplan_ros.search.goal import Goal
from trajplan_ros.search.objective import Objective
from trajplan_ros.search.polish import linearise_at


def velocity_limited_arm() -> ArmModel:
    """Return the paper's arm with two joints slower than the default omega (0.2 rad/s)."""
    arm = paper_arm()
    return ArmModel.from_dh(*arm.dh, sign=arm.sign, offset=arm.offset, lower=arm.lower,
                            upper=arm.upper, velocity=[0.2, 0.05, 1.0, 0.1, 1.0], planned=4)


def test_the_servo_law_is_eq_10() -> None:
    law = servo_law(np.array([0.2, 0.05, 0.1]))
    assert law.kind == SERVO
    assert joint_time(law, 1, 0.3) == 0.3 / 0.05
    x = np.random.default_rng(0).uniform(-2, 2, (50, 3))
    start = np.array([0.1, -0.2, 0.3])
    np.testing.assert_array_equal(motion_times(law, x, start),
                                  np.max(np.abs(x - start) / law.velocity, axis=1))


def test_every_motion_time_of_the_core_comes_from_the_objectives_law() -> None:
    # the objective, its linearisation and the fuzzy rules' longest time all read the law;
    # given a law twice as fast, the linearisation's motion times halve
    obj = Objective(velocity_limited_arm(), Goal([0.15, 0.19, 0.17]), np.zeros(5))
    np.testing.assert_array_equal(obj.law.velocity, [0.2, 0.05, 0.2, 0.1])
    x = np.random.default_rng(1).uniform(obj.lower, obj.upper, (20, 4))
    expected = np.max(np.abs(x) / obj.law.velocity, axis=1)
    np.testing.assert_allclose(obj.motion_time(x), expected, rtol=1e-15)
    np.testing.assert_allclose(obj(x).motion_time, expected, rtol=1e-15)
    np.testing.assert_allclose(linearise_at(obj.problem, x, 1.0, 1).time, expected, rtol=1e-15)
    faster = obj.problem._replace(law=servo_law(2 * obj.law.velocity))
    np.testing.assert_allclose(linearise_at(faster, x, 1.0, 1).time, expected / 2, rtol=1e-15)
    assert obj.longest_time == np.max((obj.upper - obj.lower) / obj.law.velocity)


def test_a_law_the_kernels_do_not_know_is_refused() -> None:
    law = servo_law(np.array([0.2]))._replace(kind=99)
    with pytest.raises(ValueError, match='unknown time law'):
        joint_time(law, 0, 1.0)


def ruckig_duration(distance: float, v: float, a: float, j: float) -> float:
    """Return Ruckig's minimum duration of a rest-to-rest move of one degree of freedom."""
    inp = ruckig.InputParameter(1)
    inp.current_position, inp.target_position = [0.0], [distance]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v], [a], [j]
    out = ruckig.Trajectory(1)
    assert ruckig.Ruckig(1).calculate(inp, out) == ruckig.Result.Working
    return out.duration


@pytest.mark.parametrize('kind', [TRAPEZOIDAL, JERK_LIMITED])
def test_the_profiles_last_as_long_as_ruckigs_fastest(kind: int) -> None:
    # limits and moves over four decades each way: every branch of both closed forms
    rng = np.random.default_rng(3 + kind)
    for _ in range(400):
        v, a, j = np.exp(rng.uniform(-3, 3, 3))
        d = float(np.exp(rng.uniform(-8, 3)))
        law = TimeLaw(kind, np.array([v]), np.array([a]),
                      np.array([j if kind == JERK_LIMITED else np.inf]))
        t = joint_time(law, 0, d)
        assert t == pytest.approx(ruckig_duration(d, v, a, law.jerk[0]), rel=1e-12, abs=1e-13)
        assert joint_reach(law, 0, t) == pytest.approx(d, rel=1e-12)     # t^-1(t(d)) = d


@pytest.mark.parametrize('kind', [SERVO, TRAPEZOIDAL, JERK_LIMITED])
def test_times_increase_with_the_move_and_start_at_zero(kind: int) -> None:
    law = TimeLaw(kind, np.array([0.7]), np.array([1.3]), np.array([2.9]))
    d = np.linspace(0.0, 5.0, 2001)
    t = np.array([joint_time(law, 0, x) for x in d])
    assert t[0] == 0.0 and np.all(np.diff(t) > 0)
    np.testing.assert_allclose([joint_reach(law, 0, x) for x in t], d, rtol=1e-12, atol=1e-15)


def test_the_polish_scales_each_joint_where_it_would_tie_with_the_motion_time() -> None:
    # omega T / t_i^-1(T) at T = R(x): the slowest joint's scaled displacement is omega R; under
    # the servo law, omega / v_i whatever x
    law = TimeLaw(TRAPEZOIDAL, np.array([0.5, 1.0, 2.0]), np.array([1.0, 0.5, 4.0]),
                  np.full(3, np.inf))
    x = np.random.default_rng(4).uniform(-2, 2, (30, 3))
    start = np.zeros(3)
    scales = tie_scales(law, x, start, 0.2)
    r = motion_times(law, x, start)
    np.testing.assert_allclose(np.max(np.abs(x) * scales, axis=1), 0.2 * r, rtol=1e-12)
    for k in range(30):
        reach = [joint_reach(law, i, r[k]) for i in range(3)]
        np.testing.assert_allclose(scales[k] * reach, 0.2 * r[k], rtol=1e-12)
    servo = servo_law(law.velocity)
    np.testing.assert_array_equal(tie_scales(servo, x, start, 0.2),
                                  np.broadcast_to(0.2 / law.velocity, x.shape))
