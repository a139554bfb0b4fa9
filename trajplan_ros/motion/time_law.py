# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The time law of each joint: how long it takes to turn by d rad from rest to rest, compiled.

Eq. (10) is the paper's servo law: every joint turns at its angular velocity v_i from the start,
so joint i needs t_i(d) = d / v_i and the motion takes R = max_i t_i(|q_i - q_start_i|). The
kernels that compute R take the law as an input (``TimeLaw``: a law id and its per-joint
limits): F, the polish's merit, linearisation and steps, the curve search's keys and bounds.
Two more laws are rest-to-rest profiles that respect each joint's limits (``profile``):

- TRAPEZOIDAL (v, a): t = d / v + v / a if d >= v^2 / a, else 2 sqrt(d / a);
- JERK_LIMITED (v, a, j): T_a = v / a + a / j if v j >= a^2, else 2 sqrt(v / j) (the time to
  reach v from rest and back); t = d / v + T_a if d >= v T_a; else, if v j >= a^2 and
  d >= 2 a^3 / j^2, t = a / j + sqrt(a^2 / j^2 + 4 d / a); else t = 4 (d / (2 j))^(1/3).

Each t_i is increasing, so {R <= T} is the box |d_i| <= t_i^-1(T) (``joint_reach``): the
polish's closed-form steps minimise max_i |d_i| T / t_i^-1(T) at the candidate's own R = T
(``tie_scales``), which is R itself wherever a joint ties with R, and whose fixed points are the
true problem's (the pieces' gradients differ by positive factors only).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from trajplan_ros.kinematics.jit import kernel

__all__ = ['JERK_LIMITED', 'SERVO', 'TRAPEZOIDAL', 'TimeLaw', 'joint_reach', 'joint_time',
           'motion_times', 'servo_law', 'tie_scales']

#: The law ids: SERVO is eq. (10), t = d / v_i; the other two are rest-to-rest profiles.
SERVO = 0
TRAPEZOIDAL = 1
JERK_LIMITED = 2


class TimeLaw(NamedTuple):
    """Each planned joint's time law, as the kernels take it: its id and limits."""

    kind: int                  # SERVO, TRAPEZOIDAL or JERK_LIMITED
    velocity: np.ndarray       # (m,) rad/s, v_i (omega_i of eq. 10)
    acceleration: np.ndarray   # (m,) rad/s^2 (inf under SERVO)
    jerk: np.ndarray           # (m,) rad/s^3 (inf but under JERK_LIMITED)


def servo_law(speeds: np.ndarray) -> TimeLaw:
    """Return eq. (10)'s law for joints turning at ``speeds`` (rad/s) each."""
    speeds = np.array(speeds, dtype=float)
    return TimeLaw(SERVO, speeds, np.full(speeds.shape, np.inf), np.full(speeds.shape, np.inf))


@kernel
def ramp_time(v: float, a: float, j: float) -> float:
    """Return T_a: the time (s) a jerk-limited joint takes to reach v from rest and back to it."""
    return v / a + a / j if v * j >= a * a else 2.0 * np.sqrt(v / j)


@kernel
def joint_time(law: TimeLaw, i: int, d: float) -> float:
    """Return t_i(d): the time (s) joint i needs to turn by d >= 0 rad from rest to rest."""
    v = law.velocity[i]
    if law.kind == SERVO:
        return d / v
    a = law.acceleration[i]
    if law.kind == TRAPEZOIDAL:
        return d / v + v / a if d >= v * v / a else 2.0 * np.sqrt(d / a)
    if law.kind != JERK_LIMITED:
        raise ValueError('unknown time law')
    j = law.jerk[i]
    ramp = ramp_time(v, a, j)
    if d >= v * ramp:
        return d / v + ramp
    if v * j >= a * a and d >= 2.0 * a ** 3 / (j * j):
        return a / j + np.sqrt(a * a / (j * j) + 4.0 * d / a)
    return 4.0 * np.cbrt(d / (2.0 * j))


@kernel
def joint_reach(law: TimeLaw, i: int, t: float) -> float:
    """Return t_i^-1(t): the largest turn (rad) joint i makes from rest to rest in t >= 0 s."""
    v = law.velocity[i]
    if law.kind == SERVO:
        return v * t
    a = law.acceleration[i]
    if law.kind == TRAPEZOIDAL:
        return v * (t - v / a) if t >= 2.0 * v / a else a * t * t / 4.0
    if law.kind != JERK_LIMITED:
        raise ValueError('unknown time law')
    j = law.jerk[i]
    ramp = ramp_time(v, a, j)
    if t >= 2.0 * ramp:
        return v * (t - ramp)
    if v * j >= a * a and t >= 4.0 * a / j:
        return a * ((t - a / j) ** 2 - a * a / (j * j)) / 4.0
    return 2.0 * j * (t / 4.0) ** 3


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


@kernel
def tie_scales(law: TimeLaw, x: np.ndarray, start: np.ndarray, omega: float) -> np.ndarray:
    """
    Return omega T / t_i^-1(T) (K, m) at each row's motion time T = R(x) (see the module).

    omega times the factor that turns joint i's displacement into time where it ties with T;
    omega / v_i under SERVO, whatever T; at T = 0 (x at the start) the servo's ratio.
    """
    times = motion_times(law, x, start)
    out = np.empty(x.shape)
    for k in range(x.shape[0]):
        for i in range(x.shape[1]):
            reach = joint_reach(law, i, times[k])
            servo = law.kind == SERVO or not reach > 0.0
            out[k, i] = omega / law.velocity[i] if servo else omega * times[k] / reach
    return out
