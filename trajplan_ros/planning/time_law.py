# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The time law of each joint: how long it takes to turn by d rad from rest to rest, compiled.

Eq. (10) is the paper's servo law: every joint turns at its angular velocity omega_i from the
start, so joint i needs t_i(d) = d / omega_i and the motion takes R = max_i t_i(|q_i - q_start_i|).
The kernels that compute R take the law as an input (``TimeLaw``: a law id and its per-joint
parameters) instead of hard-coding d / omega_i: F, the polish's merit and linearisation, the
curve search's keys and bounds. Another monotone law (an acceleration- or jerk-limited profile)
is a new id in ``joint_time``. What it does not reach yet: the polish's closed-form steps (the
line searches and the SQP step over active sets) minimise the servo law's scaled displacements
(``Problem.scale``, omega / omega_i); under another law they must be rebuilt on t_i's inverse.
Only SERVO exists, and ``joint_time`` refuses any other id.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from trajplan_ros.kinematics.jit import kernel

__all__ = ['SERVO', 'TimeLaw', 'joint_time', 'motion_times', 'servo_law']

#: The law ids: SERVO is eq. (10), t = d / omega_i.
SERVO = 0


class TimeLaw(NamedTuple):
    """Each planned joint's time law, as the kernels take it: its id and parameters."""

    kind: int                  # SERVO
    velocity: np.ndarray       # (m,) rad/s, omega_i
    acceleration: np.ndarray   # (m,) rad/s^2 (unused by SERVO)
    jerk: np.ndarray           # (m,) rad/s^3 (unused by SERVO)


def servo_law(speeds: np.ndarray) -> TimeLaw:
    """Return eq. (10)'s law for joints turning at ``speeds`` (rad/s) each."""
    speeds = np.array(speeds, dtype=float)
    return TimeLaw(SERVO, speeds, np.full(speeds.shape, np.inf), np.full(speeds.shape, np.inf))


@kernel
def joint_time(law: TimeLaw, i: int, d: float) -> float:
    """Return t_i(d): the time (s) joint i needs to turn by d >= 0 rad from rest to rest."""
    if law.kind != SERVO:
        raise ValueError('unknown time law')
    return d / law.velocity[i]


@kernel
def motion_times(law: TimeLaw, x: np.ndarray, start: np.ndarray) -> np.ndarray:
    """Return R of eq. (10), max_i t_i(|x_i - start_i|), for each row of x (K, m)."""
    out = np.empty(x.shape[0])
    for k in range(x.shape[0]):
        longest = 0.0
        for i in range(x.shape[1]):
            longest = max(longest, joint_time(law, i, abs(x[k, i] - start[i])))
        out[k] = longest
    return out
