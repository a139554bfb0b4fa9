# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The joints' time law (eq. 10) as an input of the kernels that compute the motion time."""
from __future__ import annotations

import numpy as np
import pytest

from trajplan_ros import ArmModel, paper_arm
from trajplan_ros.planning.objective import Objective
from trajplan_ros.planning.polish import linearise_at
from trajplan_ros.planning.time_law import joint_time, motion_times, SERVO, servo_law


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
    obj = Objective(velocity_limited_arm(), [0.15, 0.19, 0.17], np.zeros(5))
    np.testing.assert_array_equal(obj.law.velocity, [0.2, 0.05, 0.2, 0.1])
    x = np.random.default_rng(1).uniform(obj.lower, obj.upper, (20, 4))
    expected = np.max(np.abs(x) / obj.law.velocity, axis=1)
    np.testing.assert_allclose(obj.motion_time(x), expected, rtol=1e-15)
    np.testing.assert_allclose(obj(x).motion_time, expected, rtol=1e-15)
    np.testing.assert_allclose(linearise_at(obj.problem, x, 1.0, 1)[1], expected, rtol=1e-15)
    faster = obj.problem._replace(law=servo_law(2 * obj.law.velocity))
    np.testing.assert_allclose(linearise_at(faster, x, 1.0, 1)[1], expected / 2, rtol=1e-15)
    assert obj.longest_time == np.max((obj.upper - obj.lower) / obj.law.velocity)


def test_a_law_the_kernels_do_not_know_is_refused() -> None:
    law = servo_law(np.array([0.2]))._replace(kind=SERVO + 1)
    with pytest.raises(ValueError, match='unknown time law'):
        joint_time(law, 0, 1.0)
