# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The arms and profiles the profile tests run on, and the check of one motion under the controller.

``check_under_the_controller`` samples a message densely as joint_trajectory_controller does
(``controller_interpolation``, the first segment from the start at rest): the commanded
velocity and acceleration stay within each joint's limits to 1e-6 relative and the jerk to
1e-3, the motion starts and ends exactly at the start and the goal, at rest, and its duration
is Ruckig's fastest for the same move and limits, or a few gaps between phase boundaries longer.
"""
from __future__ import annotations

from pathlib import Path

from controller_interpolation import ControllerTrajectory, CUBIC, QUINTIC, validate_trajectory_msg
import numpy as np
import pytest
import ruckig
from trajplan_ros import ArmModel
from trajplan_ros.motion.motion_profile import MotionProfile, Timing
from trajplan_ros.motion.time_law import JERK_LIMITED, motion_times, TimeLaw
from trajplan_ros.motion.trajectory import _profiles, motion_points, motion_trajectory
from trajplan_ros.tools.bench.cases import PUBLISHED

__all__ = ['arm_of', 'check_under_the_controller', 'MS', 'profiles', 'ruckig_duration']

MS = 1_000_000              # ns per millisecond
PANDA_LIMITS = Path(__file__).parent / 'data' / 'panda_joint_limits.yaml'


def arm_of(name: str) -> ArmModel:
    """Return a published arm of example-robot-data."""
    arm = PUBLISHED[name]
    return ArmModel.from_urdf(arm.urdf, arm.base_link, arm.tip_link)


def profiles(name: str) -> dict[str, MotionProfile]:
    """Return the profiles the tests run on arm ``name``, by label."""
    if name == 'panda':                  # MoveIt's limits file, jerks included
        make = lambda **kw: MotionProfile.from_file(PANDA_LIMITS, **kw)  # noqa: E731
    else:                                # no published limits: the settings for every joint
        make = lambda **kw: MotionProfile(max_acceleration=12.0, max_jerk=150.0,  # noqa: E731
                                          **kw)
    return {f'{p}-{t}': make(profile=p, timing=t)
            for p in ('trapezoidal', 'jerk_limited') for t in ('independent', 'synchronized')}


def ruckig_duration(start: np.ndarray, goal: np.ndarray, law: TimeLaw, synchronized: bool
                    ) -> float:
    """Return Ruckig's fastest duration from start to goal at rest, within ``law``'s limits."""
    n = start.size
    inp = ruckig.InputParameter(n)
    inp.current_position, inp.target_position = start.tolist(), goal.tolist()
    inp.max_velocity, inp.max_acceleration = law.velocity.tolist(), law.acceleration.tolist()
    inp.max_jerk = law.jerk.tolist()
    inp.synchronization = (ruckig.Synchronization.Time if synchronized
                           else ruckig.Synchronization.No)
    out = ruckig.Trajectory(n)
    assert ruckig.Ruckig(n).calculate(inp, out) == ruckig.Result.Working
    return out.duration


def check_under_the_controller(start: np.ndarray, goal: np.ndarray, law: TimeLaw,
                               timing: Timing, names: tuple[str, ...]) -> None:
    """Check one motion's message under the controller, as the module says."""
    traj = motion_trajectory(start, goal, law, timing, sample_period=0.1, joint_names=names)
    msg = traj.to_dict()
    assert validate_trajectory_msg(msg, joints=names) is None
    assert len(traj.times) == motion_points(start, goal, law, timing, 0.1)
    assert np.all(np.diff(traj.nanoseconds) > 0) and traj.nanoseconds[0] > 0
    assert (traj.accelerations is not None) == (law.kind == JERK_LIMITED)
    # the duration: Ruckig's fastest (R of the planner's objective) to 1e-6 s
    fastest = float(motion_times(law, goal[None], start)[0])
    synchronized = timing is Timing.SYNCHRONIZED
    assert fastest == pytest.approx(ruckig_duration(start, goal, law, synchronized), abs=1e-9)
    gap = _profiles(start, goal, law, timing).first_ns / 1e9
    assert fastest - 1e-15 <= traj.duration <= fastest + 4.0 * gap + 1e-6
    controller = ControllerTrajectory(msg, {'positions': start.tolist(),
                                            'velocities': [0.0] * start.size,
                                            'accelerations': [0.0] * start.size})
    segments = controller.segments()
    assert {s.kind for s in segments} == {QUINTIC if law.kind == JERK_LIMITED else CUBIC}
    ends = np.array([[s.t0_ns, s.t0_ns + 1, (s.t0_ns + s.t1_ns) // 2, s.t1_ns - 1]
                     for s in segments]).ravel()
    times = np.unique(np.concatenate((np.arange(0, controller.end_ns + 100 * MS, MS), ends)))
    out = controller.sample(times)
    assert out.valid.all()
    assert np.max(np.abs(out.velocities) / law.velocity) <= 1 + 1e-6
    assert np.max(np.abs(out.accelerations) / law.acceleration) <= 1 + 1e-6
    if law.kind == JERK_LIMITED:
        assert max(float(np.max(s.max_abs_jerk() / law.jerk)) for s in segments) <= 1 + 1e-3
    np.testing.assert_array_equal(out.positions[0], start)
    after = times >= controller.end_ns
    held = np.broadcast_to(goal, (int(after.sum()), goal.size))
    np.testing.assert_array_equal(out.positions[after], held)
    np.testing.assert_array_equal(out.velocities[after], 0.0)
    np.testing.assert_array_equal(out.accelerations[after], 0.0)
