# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Joint trajectory of the paper's servo model: every joint turns at one fixed angular velocity.

Joint i leaves q_start_i at t = 0 towards q_goal_i at +-omega and stops when it arrives, at
t_i = |q_goal_i - q_start_i| / omega; the motion ends at R = max_i t_i (eq. 10). The trajectory
is sampled every ``sample_period`` seconds, plus one point at each joint's arrival and at the
end, so the samples are exact corners of the motion. Points carry positions and velocities;
the last has zero velocity everywhere. Times are strictly increasing and above zero, the form
joint_trajectory_controller accepts (the first point is not the start itself).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ['Trajectory', 'servo_trajectory']

#: Times closer than this (s) are one time: a microsecond, 1000 times a message's nanosecond.
_RESOLUTION = 1e-6


@dataclass(frozen=True)
class Trajectory:
    """Time-stamped joint positions (rad) and velocities (rad/s), one row per point."""

    joint_names: tuple[str, ...]
    times: np.ndarray          # (T,) s from start, strictly increasing, > 0
    positions: np.ndarray      # (T, n_joints)
    velocities: np.ndarray     # (T, n_joints)

    @property
    def duration(self) -> float:
        """Return the time of the last point, s."""
        return float(self.times[-1])

    def sample(self, t: np.ndarray) -> np.ndarray:
        """Return positions at times t (clamped to [0, duration]) by linear interpolation."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        start = self.positions[0] - self.velocities[0] * self.times[0]
        times = np.concatenate(([0.0], self.times))
        pos = np.vstack((start, self.positions))
        return np.stack([np.interp(t, times, pos[:, j]) for j in range(pos.shape[1])], axis=-1)


def servo_trajectory(start: np.ndarray, goal: np.ndarray, omega: float, *,
                     sample_period: float = 0.1,
                     joint_names: tuple[str, ...] | None = None) -> Trajectory:
    """
    Return the fixed-angular-velocity motion from ``start`` to ``goal`` ((n_joints,), rad).

    A start equal to the goal (or within a microsecond of motion of it) gives one point at
    ``sample_period`` with zero velocity. A joint whose own motion is that short is not sampled
    at its arrival, so no point lands at the start itself.
    """
    start = np.asarray(start, dtype=float)
    goal = np.asarray(goal, dtype=float)
    if start.shape != goal.shape or start.ndim != 1:
        raise ValueError('start and goal must be joint vectors of the same length')
    if not (np.isfinite(omega) and omega > 0
            and np.isfinite(sample_period) and sample_period > 0):
        raise ValueError('omega and sample_period must be finite and positive')
    names = joint_names or tuple(f'joint{i + 1}' for i in range(start.size))
    delta = goal - start
    arrive = np.abs(delta) / omega
    duration = float(arrive.max())
    if duration <= _RESOLUTION:
        t = np.array([sample_period])
    else:
        grid = np.arange(1, int(np.floor(duration / sample_period)) + 1) * sample_period
        t = np.unique(np.concatenate((grid, arrive, [duration])))
        t = t[(t > _RESOLUTION) & (t <= duration)]
        # merge samples closer than a microsecond (a grid point on an arrival time)
        t = t[np.concatenate((np.diff(t) > _RESOLUTION, [True]))]
        t[-1] = duration
    direction = np.sign(delta)
    moving = t[:, None] < arrive[None, :] - 1e-12
    positions = start + direction * omega * np.minimum(t[:, None], arrive[None, :])
    positions[-1] = goal
    velocities = np.where(moving, direction * omega, 0.0)
    return Trajectory(tuple(names), t, positions, velocities)
