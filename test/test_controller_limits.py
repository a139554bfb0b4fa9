# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Random moves on random limits under joint_trajectory_controller: within every limit.

For every law (servo, trapezoidal, jerk-limited) and timing, on the SO-101, the Panda and the
paper's arm, seeded random moves on per-joint limits log-uniform over four decades each
(``controller_limits``): the controller's polynomials keep every velocity and acceleration
within its limit to 1e-6 relative and every jerk to 1e-3, the motion ends at the goal at rest,
and it lasts the fastest duration R, or a few gaps between boundaries longer (see
``rest_to_rest``). ``controller_check.py random`` runs the same over 20 000 moves each. The
fast check itself is the controller's arithmetic: its polynomials are
``controller_interpolation``'s bit for bit, its peaks those of dense sampling or above.
"""
from __future__ import annotations

from controller_interpolation import ControllerTrajectory
from controller_limits import _coefficients, controller_peaks, peaks, random_law, random_move
import numpy as np
from profile_cases import arm_of
import pytest
from trajplan_ros import paper_arm
from trajplan_ros.motion.motion_profile import Timing
from trajplan_ros.motion.time_law import JERK_LIMITED, SERVO, TRAPEZOIDAL
from trajplan_ros.motion.trajectory import _profiles, motion_trajectory

ARMS = {'so101': lambda: arm_of('so101'), 'panda': lambda: arm_of('panda'), 'paper': paper_arm}
LAWS = {'servo': SERVO, 'trapezoidal': TRAPEZOIDAL, 'jerk_limited': JERK_LIMITED}


@pytest.mark.parametrize('name', list(ARMS))
@pytest.mark.parametrize('law_name', list(LAWS))
@pytest.mark.parametrize('timing', list(Timing))
def test_random_moves_on_random_limits_keep_every_limit(name: str, law_name: str,
                                                        timing: Timing) -> None:
    arm = ARMS[name]()
    kind = LAWS[law_name]
    rng = np.random.default_rng([97, kind, timing is Timing.SYNCHRONIZED, len(name)])
    for k in range(40):
        start, goal, law = random_move(rng, arm, random_law(rng, kind, arm.n_joints), k)
        p = peaks(start, goal, law, timing)
        assert not p.over(law), (k, p)
        assert p.fastest - 1e-15 <= p.duration
        if kind != SERVO:         # a few of the gaps between boundaries at most
            gaps = _profiles(start, goal, law, timing).first_ns / 1e9
            assert p.duration <= p.fastest + 4.0 * gaps + 1e-6, (k, p)


@pytest.mark.parametrize('kind', [SERVO, TRAPEZOIDAL, JERK_LIMITED])
def test_the_fast_check_is_the_controllers_arithmetic(kind: int) -> None:
    arm = arm_of('panda')
    rng = np.random.default_rng(5 + kind)
    checked = 0
    for k in range(12):           # short moves, of at most 100 points (the reproduction is slow)
        start, goal, law = random_move(rng, arm, random_law(rng, kind, arm.n_joints), k)
        goal = start + 0.1 * (goal - start)
        timing = list(Timing)[k % 2]
        traj = motion_trajectory(start, goal, law, timing, sample_period=0.1)
        if len(traj.times) > 100:
            continue
        checked += 1
        controller = ControllerTrajectory(traj.to_dict(), {
            'positions': start.tolist(), 'velocities': [0.0] * start.size,
            'accelerations': [0.0] * start.size})
        segments = controller.segments()
        _, coefficients, _ = _coefficients(traj)
        np.testing.assert_array_equal(coefficients,
                                      np.stack([s.coefficients for s in segments]))
        # its peaks: those of the controller's samples at 1 ms and at every segment's ends, or
        # (between samples) a little above
        times = np.unique(np.concatenate((
            np.arange(0, controller.end_ns, 1_000_000),
            np.array([[s.t0_ns, s.t0_ns + 1, s.t1_ns - 1] for s in segments]).ravel())))
        out = controller.sample(times)
        sampled = [np.max(np.abs(out.velocities) / law.velocity),
                   np.max(np.abs(out.accelerations) / law.acceleration),
                   max(float(np.max(s.max_abs_jerk() / law.jerk)) for s in segments)]
        fast = controller_peaks(traj, law)
        for found, seen in zip(fast, sampled):
            assert seen * (1.0 - 1e-12) <= found <= seen * (1.0 + 1e-6) + 1e-300
    assert checked >= 3
