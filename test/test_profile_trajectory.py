# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Profile trajectories under joint_trajectory_controller's interpolation: within every limit.

Each message is checked as ``profile_cases.check_under_the_controller`` says. Its duration R
is Ruckig's fastest for the same move and limits, with time synchronisation and without, to
1e-9 s; the message lasts R, or a few gaps between phase boundaries longer where a phase of the
slowest joint is shorter than one (``rest_to_rest``).
"""
from __future__ import annotations

import numpy as np
from profile_cases import arm_of, check_under_the_controller, profiles, ruckig_duration
import pytest
from trajplan_ros import plan
from trajplan_ros.motion.motion_profile import Timing
from trajplan_ros.motion.rest_to_rest import GAP_NS, joint_profiles
from trajplan_ros.motion.time_law import JERK_LIMITED, motion_times, SERVO, TimeLaw, TRAPEZOIDAL
from trajplan_ros.motion.trajectory import motion_trajectory


@pytest.mark.parametrize('name', ['panda', 'so101'])
@pytest.mark.parametrize('label', ['trapezoidal-independent', 'trapezoidal-synchronized',
                                   'jerk_limited-independent', 'jerk_limited-synchronized'])
def test_random_moves_keep_every_limit_under_the_controller(name: str, label: str) -> None:
    arm = arm_of(name)
    profile = profiles(name)[label]
    law = profile.time_law(arm, omega=100.0)          # the URDF's and the file's velocities
    rng = np.random.default_rng(40 + len(label) + len(name))
    for k in range(25):
        start, goal = rng.uniform(arm.lower, arm.upper, (2, arm.n_joints))
        if k % 5 == 0:
            goal[::3] = start[::3]                    # some joints stay
        check_under_the_controller(start, goal, law, profile.timing, arm.joint_names)


@pytest.mark.parametrize('name', ['panda', 'so101'])
def test_planned_motions_keep_every_limit_under_the_controller(name: str) -> None:
    arm = arm_of(name)
    rng = np.random.default_rng(7)
    q, starts = rng.uniform(arm.lower, arm.upper, (2, 16, arm.n_joints))
    for k in range(16):             # the planner's answers: joints often tie at R
        profile = list(profiles(name).values())[k % 4]
        result = plan(arm.tool(q[k:k + 1])[0][0], starts[k], arm=arm, angular_velocity=100.0,
                      motion=profile, seed=k)
        assert result.success, result.message
        law = profile.time_law(arm, 100.0)
        assert result.motion_time_s == pytest.approx(
            ruckig_duration(result.start, result.joint_goal, law, False), abs=1e-9)
        assert result.to_dict()['profile'] == profile.profile.value
        traj = result.trajectory(arm)
        assert result.trajectory_points(arm) == len(traj.times)
        check_under_the_controller(result.start, result.joint_goal, law, profile.timing,
                                   arm.joint_names)


def test_each_joint_follows_its_own_profile_without_synchronisation() -> None:
    # independent: a joint that is not the slowest arrives at its own fastest time (up to the
    # whole nanoseconds and the gaps between boundaries, GAP_NS a few times), not at the end
    law = TimeLaw(JERK_LIMITED, np.array([1.0, 1.0, 2.0]), np.array([2.0, 2.0, 4.0]),
                  np.array([20.0, 20.0, 40.0]))
    start, goal = np.zeros(3), np.array([2.0, 0.3, -0.5])
    alone = joint_profiles(goal - start, *law[1:]).ends_ns / 1e9
    together = joint_profiles(goal - start, *law[1:], synchronized=True).ends_ns / 1e9
    own = [float(motion_times(law._replace(velocity=law.velocity[i:i + 1],
                                           acceleration=law.acceleration[i:i + 1],
                                           jerk=law.jerk[i:i + 1]),
                              goal[None, i:i + 1], start[i:i + 1])[0]) for i in range(3)]
    assert np.all(alone >= own) and np.all(alone <= np.array(own) + 4e-3)
    assert alone[1] < alone[0] - 0.5 and alone[2] < alone[0] - 0.5
    np.testing.assert_array_equal(together, together[0])
    assert together[0] == pytest.approx(own[0], abs=1e-6)


def test_servo_timing_is_the_papers_or_a_straight_line() -> None:
    law = TimeLaw(SERVO, np.array([0.2, 0.1]), np.full(2, np.inf), np.full(2, np.inf))
    start, goal = np.zeros(2), np.array([0.4, 0.1])
    own = motion_trajectory(start, goal, law, Timing.INDEPENDENT)
    line = motion_trajectory(start, goal, law, Timing.SYNCHRONIZED)
    assert own.velocities is None and line.velocities is None          # positions only
    assert own.duration == line.duration == pytest.approx(2.0)
    np.testing.assert_allclose(line.positions / goal, np.broadcast_to(
        (line.times / 2.0)[:, None], line.positions.shape), rtol=1e-12)
    assert own.positions[own.times == 1.0][0][1] == pytest.approx(0.1)   # joint 2 arrived


@pytest.mark.parametrize('label', ['trapezoidal-independent', 'trapezoidal-synchronized',
                                   'jerk_limited-independent', 'jerk_limited-synchronized'])
def test_joints_that_tie_share_their_boundaries(label: str) -> None:
    # equal limits and turns 4e-8 rad apart, as the planner's ties are: their boundaries would
    # be nanoseconds apart; the nearer one takes the other's phases
    arm = arm_of('so101')
    profile = profiles('so101')[label]
    law = profile.time_law(arm, 100.0)
    start = np.array([0.085, -0.073, 0.139, -0.951, 1.605])
    goal = start + np.array([-1.33068341, 0.0195, -0.6005, 0.3475, -1.33068345])
    check_under_the_controller(start, goal, law, profile.timing, arm.joint_names)
    phases = joint_profiles(goal - start, *law[1:], synchronized=profile.timing
                            is Timing.SYNCHRONIZED).durations_ns
    np.testing.assert_array_equal(phases[0], phases[4])


SHORT_PHASES = {   # the slowest joint's own phases shorter than the gap between boundaries
    'jerk phases of a / j = 11 us': (
        TimeLaw(JERK_LIMITED, np.array([52.26, 0.967]), np.array([0.0327, 49.3]),
                np.array([2947.0, 0.539])),
        np.array([-1.3294, -1.3710]), np.array([0.7881, -2.5163])),
    'rises of v / a = 23 us': (
        TimeLaw(TRAPEZOIDAL, np.array([7.4043494, 0.01527386]),
                np.array([0.585052537, 674.803721]), np.full(2, np.inf)),
        np.array([-1.466369, 0.3300351]), np.array([-0.90486946, 0.79900072])),
}


@pytest.mark.parametrize('timing', list(Timing))
@pytest.mark.parametrize('case', list(SHORT_PHASES))
def test_the_slowest_joints_short_phases_are_lengthened(case: str, timing: Timing) -> None:
    # kept as they were, they made segments of microseconds, over which the positions'
    # rounding gave the other joint 178 times its jerk limit (or 1 + 8e-6 its acceleration)
    law, start, goal = SHORT_PHASES[case]
    check_under_the_controller(start, goal, law, timing, ('joint1', 'joint2'))
    traj = motion_trajectory(start, goal, law, timing)
    assert np.diff(traj.nanoseconds).min() >= GAP_NS and traj.nanoseconds[0] >= GAP_NS
    fastest = float(motion_times(law, goal[None], start)[0])
    assert traj.duration - fastest < 2e-3             # the price: under 2 ms on 16 s and 31 s


def test_a_turn_of_a_few_ulp_is_none() -> None:
    # a planned joint one ulp from its start (the polish's answers have them): not a profile
    # of a zero-length ramp, no NaN
    arm = arm_of('so101')
    for label in ('trapezoidal-synchronized', 'jerk_limited-synchronized'):
        profile = profiles('so101')[label]
        start = np.array([0.5, -0.2, 0.9, 0.1, 0.0])
        goal = start + np.array([0.8, 2.2e-16, -0.4, 0.0, 1e-13])
        law = profile.time_law(arm, 100.0)
        traj = motion_trajectory(start, goal, law, profile.timing)
        assert np.all(np.isfinite(traj.velocities))
        check_under_the_controller(start, goal, law, profile.timing, arm.joint_names)
