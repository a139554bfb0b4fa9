# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
How far a published motion comes to its limits under joint_trajectory_controller, fast.

``controller_peaks`` computes every segment's polynomial as ``controller_interpolation`` does
(the controller's arithmetic, operation for operation, over all segments at once: the same
doubles) from the state at rest at the start, and returns the largest |velocity|,
|acceleration| and |jerk| over the whole motion relative to each joint's limit: the jerk and
the acceleration at their extremes inside each segment (the ends and where their derivative is
zero), the velocity at each segment's ends, at 7 instants inside it and where the
acceleration's linear and quadratic parts cross zero (the polynomials evaluated in Horner's
form). After the last point the controller holds it, at rest.

``random_law`` and ``random_move`` draw the property test's and the benchmark's cases: per-joint
limits log-uniform over four decades each, moves across the joints' ranges, some with joints
that stay, some with joints that tie (equal limits, turns 1e-8 rad apart) and some short.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from trajplan_ros.kinematics import ArmModel
from trajplan_ros.motion.motion_profile import Timing
from trajplan_ros.motion.time_law import JERK_LIMITED, motion_times, SERVO, TimeLaw
from trajplan_ros.motion.trajectory import motion_trajectory, Trajectory

__all__ = ['LIMIT_DECADES', 'Peaks', 'controller_peaks', 'random_law', 'random_move']

#: log10 of the least and greatest velocity, acceleration and jerk limits drawn: four decades.
LIMIT_DECADES = {'velocity': (-2.0, 2.0), 'acceleration': (-1.5, 2.5), 'jerk': (-0.5, 3.5)}
#: Instants inside each segment at which the velocity is taken, besides its ends.
_INSIDE = np.arange(1, 8) / 8.0


@dataclass(frozen=True)
class Peaks:
    """A message's largest commanded values relative to the limits, and its ends."""

    velocity: float            # max |v| / v_limit over joints and time
    acceleration: float        # max |a| / a_limit (0 under the servo law)
    jerk: float                # max |j| / j_limit inside segments (0 unless jerk-limited)
    exact_ends: bool           # starts at the start and ends at the goal, at rest
    duration: float            # the last point's time, s
    fastest: float             # R: the slowest joint's fastest time, s

    def over(self, law: TimeLaw) -> bool:
        """Return whether a limit is exceeded by more than the tolerance (1e-6, jerk 1e-3)."""
        return (self.velocity > 1.0 + 1e-6 or self.acceleration > 1.0 + 1e-6
                or (law.kind == JERK_LIMITED and self.jerk > 1.0 + 1e-3)
                or not self.exact_ends)


def _coefficients(traj: Trajectory) -> tuple[np.ndarray, np.ndarray, str]:
    """Return each segment's duration (K,) s and polynomial (K, n, 6), as the controller has it."""
    zeros = np.zeros((1, traj.start.size))
    sp = np.vstack((traj.start, traj.positions[:-1]))
    ep = traj.positions
    ns = np.diff(np.concatenate(([0], traj.nanoseconds))).astype(np.int64)
    duration = ns.astype(float) / 1e9                    # rclcpp's Duration::seconds()
    c = np.zeros(sp.shape + (6,))
    c[..., 0] = sp
    if traj.velocities is None:                          # linear
        c[..., 1] = (ep - sp) / duration[:, None]
        return duration, c, 'linear'
    t1 = (1.0 * duration)[:, None]                       # generate_powers
    t2, t3 = t1 * duration[:, None], t1 * duration[:, None] * duration[:, None]
    t4, t5 = t3 * duration[:, None], t3 * duration[:, None] * duration[:, None]
    sv, ev = np.vstack((zeros, traj.velocities[:-1])), traj.velocities
    c[..., 1] = sv
    if traj.accelerations is None:                       # cubic
        c[..., 2] = (-3.0 * sp + 3.0 * ep - 2.0 * sv * t1 - ev * t1) / t2
        c[..., 3] = (2.0 * sp - 2.0 * ep + sv * t1 + ev * t1) / t3
        return duration, c, 'cubic'
    sa, ea = np.vstack((zeros, traj.accelerations[:-1])), traj.accelerations
    c[..., 2] = 0.5 * sa
    c[..., 3] = (-20.0 * sp + 20.0 * ep - 3.0 * sa * t2 + ea * t2 - 12.0 * sv * t1
                 - 8.0 * ev * t1) / (2.0 * t3)
    c[..., 4] = (30.0 * sp - 30.0 * ep + 3.0 * sa * t2 - 2.0 * ea * t2 + 16.0 * sv * t1
                 + 14.0 * ev * t1) / (2.0 * t4)
    c[..., 5] = (-12.0 * sp + 12.0 * ep - sa * t2 + ea * t2 - 6.0 * sv * t1
                 - 6.0 * ev * t1) / (2.0 * t5)
    return duration, c, 'quintic'


def _derivatives(c: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return velocity, acceleration and jerk of polynomials c (K, n, 6) at s (K, n, m) s."""
    c = [c[..., k:k + 1] for k in range(6)]
    velocity = c[1] + s * (2.0 * c[2] + s * (3.0 * c[3] + s * (4.0 * c[4] + s * 5.0 * c[5])))
    acceleration = 2.0 * c[2] + s * (6.0 * c[3] + s * (12.0 * c[4] + s * 20.0 * c[5]))
    return velocity, acceleration, 6.0 * c[3] + s * (24.0 * c[4] + s * 60.0 * c[5])


def _roots(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Return both real roots of a s^2 + b s + c (..., 2), NaN where none (stable formula)."""
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        root = np.sqrt(b * b - 4.0 * a * c)
        q = -0.5 * (b + np.where(b < 0.0, -root, root))
        first = np.where(a != 0.0, q / a, -c / b)
        second = np.where(q != 0.0, c / q, np.nan)
    return np.stack((first, second), axis=-1)


def controller_peaks(traj: Trajectory, law: TimeLaw) -> tuple[float, float, float]:
    """Return the largest |velocity|, |acceleration| and |jerk| relative to ``law``'s limits."""
    duration, c, kind = _coefficients(traj)
    T = duration[:, None, None]
    ends = np.broadcast_to(np.array([0.0, 1.0]), c.shape[:2] + (2,)) * T
    if kind == 'linear':
        return float(np.max(np.abs(c[..., 1]) / law.velocity, initial=0.0)), 0.0, 0.0
    # where the jerk is zero (the acceleration's extremes) and where the acceleration is (the
    # velocity's: its linear part's root, and its quadratic part's)
    turning = _roots(60.0 * c[..., 5], 24.0 * c[..., 4], 6.0 * c[..., 3])
    with np.errstate(divide='ignore', invalid='ignore'):
        crossing = np.concatenate(((-c[..., 2] / (3.0 * c[..., 3]))[..., None],
                                   _roots(12.0 * c[..., 4], 6.0 * c[..., 3], 2.0 * c[..., 2])),
                                  axis=-1)
    inside = np.broadcast_to(_INSIDE, c.shape[:2] + (_INSIDE.size,)) * T

    def within(s: np.ndarray) -> np.ndarray:
        return np.where(np.isfinite(s) & (s > 0.0) & (s < T), s, 0.0)

    with np.errstate(divide='ignore', invalid='ignore'):
        vertex = (-c[..., 4] / (5.0 * c[..., 5]))[..., None]        # the jerk's extreme
    s = np.concatenate((ends, inside, within(turning), within(crossing), within(vertex)),
                       axis=-1)
    velocity, acceleration, jerk = _derivatives(c, s)
    if kind == 'cubic':
        jerk = np.zeros_like(jerk)
    return (float(np.max(np.abs(velocity) / law.velocity[:, None])),
            float(np.max(np.abs(acceleration) / law.acceleration[:, None])),
            float(np.max(np.abs(jerk) / law.jerk[:, None])))


def peaks(start: np.ndarray, goal: np.ndarray, law: TimeLaw, timing: Timing) -> Peaks:
    """Return the peaks under the controller of the message ``motion_trajectory`` publishes."""
    traj = motion_trajectory(start, goal, law, timing, sample_period=0.1)
    velocity, acceleration, jerk = controller_peaks(traj, law)
    at_rest = traj.velocities is None or (not traj.velocities[-1].any() and (
        traj.accelerations is None or not traj.accelerations[-1].any()))
    exact = bool(np.array_equal(traj.positions[-1], goal) and at_rest)
    return Peaks(velocity, acceleration, jerk, exact, traj.duration,
                 float(motion_times(law, goal[None], start)[0]))


def random_law(rng: np.random.Generator, kind: int, n: int) -> TimeLaw:
    """Return a law of ``kind`` for n joints, each limit log-uniform over its decades."""
    v, a, j = (10.0 ** rng.uniform(*LIMIT_DECADES[name], n)
               for name in ('velocity', 'acceleration', 'jerk'))
    if kind == SERVO:
        a = np.full(n, np.inf)
    if kind != JERK_LIMITED:
        j = np.full(n, np.inf)
    return TimeLaw(kind, v, a, j)


def random_move(rng: np.random.Generator, arm: ArmModel, law: TimeLaw, k: int
                ) -> tuple[np.ndarray, np.ndarray, TimeLaw]:
    """
    Return move k's start, goal and law (``law``, or with two joints' limits made equal).

    Across the joints' ranges; every fifth move some joints stay, the next one two joints tie
    (same limits, turns 1e-8 rad apart), the next one is short (turns scaled by 1e-6 to 1).
    """
    start, goal = rng.uniform(arm.lower, arm.upper, (2, arm.n_joints))
    if k % 5 == 0:
        goal[::3] = start[::3]
    elif k % 5 == 1 and arm.n_joints > 1:
        i, m = rng.choice(arm.n_joints, 2, replace=False)
        law = TimeLaw(law.kind, *(np.where(np.arange(arm.n_joints) == m, x[i], x)
                                  for x in law[1:]))
        turn = goal[i] - start[i]
        goal[m] = np.clip(start[m] + np.sign(rng.uniform(-1, 1)) * (abs(turn) + 1e-8),
                          arm.lower[m], arm.upper[m])
    elif k % 5 == 2:
        goal = start + (goal - start) * 10.0 ** rng.uniform(-6.0, 0.0)
    return start, goal, law
