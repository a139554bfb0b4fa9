# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Objective F = R + S (eq. 9-14): values, modes and refused requests."""
import numpy as np
import pytest

from trajplan_ros.kinematics import paper_arm
from trajplan_ros.search.goal import Goal, InvalidRequest
from trajplan_ros.search.objective import Objective
from trajplan_ros.tools.bench.cases import PAPER_TARGET as TARGET
from trajplan_ros.tools.bench.reference import exact_minimum

ARM = paper_arm()


def test_motion_time_is_eq10():
    obj = Objective(ARM, Goal(TARGET), np.zeros(5))
    x = np.array([[0.9, 1.49, -0.23, 1.17]])
    assert obj.motion_time(x)[0] == pytest.approx(1.49 / 0.2)


def test_efficiency_at_an_exact_solution_is_r_minus_24():
    ref = exact_minimum(ARM, TARGET, np.zeros(5))
    ev = Objective(ARM, Goal(TARGET), np.zeros(5))(ref.joint_goal[None, :])
    assert ev.error[0] < 1e-15
    assert ev.efficiency[0] == pytest.approx(ref.motion_time_s - 24.0, abs=1e-4)   # F* = -19.49


def test_radial_error_vanishes_only_at_radial_solutions():
    free = exact_minimum(ARM, TARGET, np.zeros(5)).joint_goal[None, :]
    radial = exact_minimum(ARM, TARGET, np.zeros(5), mode='radial').joint_goal[None, :]
    obj = Objective(ARM, Goal(TARGET, mode='radial'), np.zeros(5))
    assert obj(radial).error[0] < 1e-12
    assert obj(free).error[0] > 1e-3


def test_fewer_axis_conditions_leave_the_axis_freer():
    # across = 1: the axis held in the plane of the goal ray and the second vector across it;
    # the error is the angle out of that plane. across = 0: the position alone.
    x = np.random.default_rng(1).uniform(ARM.lower[:4], ARM.upper[:4], (8, 4))
    full, one, none = (Objective(ARM, Goal(TARGET, mode='radial'), np.zeros(5), across=n)
                       for n in (2, 1, 0))
    tool = full.tool(x)
    p, u = tool
    assert [o.residuals(tool).shape[1] for o in (full, one, none)] == [5, 4, 3]
    out_of_plane = np.arcsin(np.abs(u @ full.ray_basis[1]))
    np.testing.assert_allclose(one.errors(tool) ** 2,
                               none.errors(tool) ** 2 + (ARM.reach * out_of_plane) ** 2)
    np.testing.assert_allclose(none.errors(tool), np.linalg.norm(p - TARGET, axis=1))
    in_plane = u - np.outer(u @ full.ray_basis[1], full.ray_basis[1])
    in_plane /= np.linalg.norm(in_plane, axis=1)[:, None]
    turned = np.stack((p, in_plane))
    assert np.all(np.abs(one.residuals(turned)[:, 3]) < 1e-15)         # on its constraints,
    np.testing.assert_allclose(one.errors(turned), none.errors(tool))  # no axis error
    with pytest.raises(ValueError, match='across'):
        Objective(ARM, Goal(TARGET, mode='radial'), np.zeros(5), across=3)


def test_vectorised_over_particles():
    obj = Objective(ARM, Goal(TARGET), np.zeros(5))
    x = np.random.default_rng(0).uniform(obj.lower, obj.upper, (64, 4))
    batch = obj(x)
    single = [obj(row[None, :]) for row in x[:3]]
    np.testing.assert_allclose(batch.efficiency[:3], [e.efficiency[0] for e in single])


@pytest.mark.parametrize('goal, start, reason', [
    ([np.nan, 0.1, 0.1], None, 'non-finite'),
    ([0.3, 0.3, 0.3], None, "beyond the arm's reach"),
    ([0.1, 0.1], None, '3 coordinates'),
    (TARGET, [0, 0, 0, 0, 4.0], 'outside its limits'),
    (TARGET, [0, 0, np.inf, 0, 0], 'non-finite'),
    (TARGET, [0, 0, 0], '5 joint angles'),
])
def test_bad_requests_are_refused_before_optimisation(goal, start, reason):
    with pytest.raises(InvalidRequest, match=reason):
        Objective(ARM, Goal(np.asarray(goal, dtype=float)),
                  np.zeros(5) if start is None else np.asarray(start, dtype=float))


def test_bad_settings_raise():
    with pytest.raises(ValueError):
        Objective(ARM, Goal(TARGET), np.zeros(5), omega=0.0)
    with pytest.raises(ValueError):
        Objective(ARM, Goal(TARGET, mode='sideways'), np.zeros(5))
