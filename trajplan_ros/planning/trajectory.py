# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Joint trajectory of the paper's servo model: every joint turns at one fixed angular velocity.

Joint i leaves q_start_i at t = 0 towards q_goal_i at +-omega and stops when it arrives, at
t_i = |q_goal_i - q_start_i| / omega (omega may be one per joint: a joint whose velocity limit is
lower turns at its limit, ``ArmModel.speeds``); the motion ends at R = max_i t_i (eq. 10). The
trajectory is sampled every ``sample_period`` seconds, plus one point at each joint's arrival
and at the end, so the samples are exact corners of the motion.

A ``Trajectory`` is what the JointTrajectory message carries. Its times are whole nanoseconds
(the message's resolution; the end rounded up), strictly increasing and above zero (the first
point is not the start itself), and each point's positions are the motion's at its rounded
time. Servo points carry positions only: joint_trajectory_controller then interpolates each
segment linearly, which is this motion exactly, never faster than omega (with velocities it
would fit cubics through the velocity steps and overshoot), but for the rounding of the
positions themselves: a few ulp over the segment, whose duration is at least a microsecond
(relative to omega about 1e-9 at 0.2 rad/s in the worst case, 1e-13 on typical plans). After
the last point the controller holds it, at rest. ``trajectory_points`` counts the points
without building them, to refuse a long trajectory first.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ['Trajectory', 'servo_trajectory', 'trajectory_points']

#: Times closer than this (s) are one time: a microsecond, 1000 times a message's nanosecond.
_RESOLUTION = 1e-6


@dataclass(frozen=True)
class Trajectory:
    """
    A joint trajectory as the JointTrajectory message carries it, from the start at t = 0.

    ``velocities`` and ``accelerations`` are None where the points do not carry them (servo
    points carry positions only).
    """

    joint_names: tuple[str, ...]
    start: np.ndarray          # (n_joints,) rad at t = 0, the state the controller starts from
    times: np.ndarray          # (T,) s from start, whole nanoseconds, strictly increasing, > 0
    positions: np.ndarray      # (T, n_joints) rad
    velocities: np.ndarray | None = None       # (T, n_joints) rad/s, or None
    accelerations: np.ndarray | None = None    # (T, n_joints) rad/s^2, or None

    @property
    def duration(self) -> float:
        """Return the time of the last point, s."""
        return float(self.times[-1])

    @property
    def nanoseconds(self) -> list[int]:
        """Return each point's time_from_start in whole nanoseconds."""
        return np.round(self.times * 1e9).astype(np.int64).tolist()

    def sample(self, t: np.ndarray) -> np.ndarray:
        """Return positions at times t (clamped to [0, duration]), linear between points."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        times = np.concatenate(([0.0], self.times))
        pos = np.vstack((self.start, self.positions))
        return np.stack([np.interp(t, times, pos[:, j]) for j in range(pos.shape[1])], axis=-1)

    def to_dict(self) -> dict[str, Any]:
        """
        Return the message as JSON-ready data: joint names and points, fields as carried.

        ``{"joint_names": [...], "points": [{"time_from_start": s, "positions": [...],
        "velocities": [...], "accelerations": [...]}]}``, an empty list where the points leave
        a field empty; ``time_from_start`` is the point's whole nanoseconds in seconds.
        """
        rows = len(self.times)
        fields = {name: (values.tolist() if values is not None else [[] for _ in range(rows)])
                  for name, values in (('positions', self.positions),
                                       ('velocities', self.velocities),
                                       ('accelerations', self.accelerations))}
        points = [{'time_from_start': ns / 1e9, 'positions': fields['positions'][k],
                   'velocities': fields['velocities'][k],
                   'accelerations': fields['accelerations'][k]}
                  for k, ns in enumerate(self.nanoseconds)]
        return {'joint_names': list(self.joint_names), 'points': points}


def _motion(start: np.ndarray, goal: np.ndarray, omega: float | np.ndarray,
            sample_period: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """
    Check the arguments; return start, goal, each joint's arrival time and the duration R.

    ``omega`` is one angular velocity for every joint or one per joint (rad/s).
    """
    start = np.asarray(start, dtype=float)
    goal = np.asarray(goal, dtype=float)
    if start.shape != goal.shape or start.ndim != 1:
        raise ValueError('start and goal must be joint vectors of the same length')
    omega = np.asarray(omega, dtype=float)
    if not (np.all(np.isfinite(omega)) and np.all(omega > 0)
            and omega.shape in ((), start.shape)
            and np.isfinite(sample_period) and sample_period > 0):
        raise ValueError('omega and sample_period must be finite and positive')
    arrive = np.abs(goal - start) / omega
    return start, goal, arrive, float(arrive.max())


def servo_trajectory(start: np.ndarray, goal: np.ndarray, omega: float | np.ndarray, *,
                     sample_period: float = 0.1,
                     joint_names: tuple[str, ...] | None = None) -> Trajectory:
    """
    Return the fixed-angular-velocity motion from ``start`` to ``goal`` ((n_joints,), rad).

    A start equal to the goal (or within a microsecond of motion of it) gives one point at
    ``sample_period``. A joint whose own motion is that short is not sampled at its arrival, so
    no point lands at the start itself. Each time is rounded to whole nanoseconds (an arrival and
    the end up, so that the joint has arrived) and the positions are computed at those times.
    """
    start, goal, arrive, duration = _motion(start, goal, omega, sample_period)
    names = joint_names or tuple(f'joint{i + 1}' for i in range(start.size))
    if duration <= _RESOLUTION:
        t = np.array([sample_period])
    else:
        grid = np.arange(1, int(np.floor(duration / sample_period)) + 1) * sample_period
        t = np.unique(np.concatenate((grid, arrive, [duration])))
        t = t[(t > _RESOLUTION) & (t <= duration)]
        # merge samples closer than a microsecond (a grid point on an arrival time)
        t = t[np.concatenate((np.diff(t) > _RESOLUTION, [True]))]
    # whole nanoseconds; an arrival (and the end) rounded up, so the joint is there by then
    ns = np.where(np.isin(t, arrive), np.ceil(t * 1e9), np.round(t * 1e9))
    ns[-1] = np.ceil(max(t[-1], duration) * 1e9)
    t = ns / 1e9
    turned = np.sign(goal - start) * omega * t[:, None]
    positions = np.where(t[:, None] >= arrive[None, :], goal, start + turned)
    positions[-1] = goal                         # its time is at least R (up to its rounding)
    return Trajectory(tuple(names), start, t, positions)


def trajectory_points(start: np.ndarray, goal: np.ndarray, omega: float | np.ndarray,
                      sample_period: float = 0.1) -> int:
    """
    Return how many points ``servo_trajectory`` gives for these arguments, without building it.

    In O(number of joints) time and memory: the grid times k * ``sample_period`` form runs of
    points one period apart, which are counted whole; only the points next to the arrivals and
    the end (eq. 10) are looked at one by one, with the same floating-point times and the same
    microsecond merging as ``servo_trajectory``. The one exception is a period within rounding
    of that microsecond, where neighbouring grid points may or may not merge: there the runs are
    counted in fixed-size chunks (bounded memory, time linear in their length).
    """
    _, _, arrive, duration = _motion(start, goal, omega, sample_period)
    if duration <= _RESOLUTION:
        return 1
    last = int(np.floor(duration / sample_period))        # grid times k * period, k = 1..last
    first = _grid_count(_RESOLUTION, sample_period, last) + 1
    final = _grid_count(duration, sample_period, last)    # grid points kept: first..final
    corners = {float(a) for a in arrive if a > _RESOLUTION} | {duration}
    # the points in sorted order, each with its grid index (None for an arrival off the grid):
    # every corner, the grid points on either side of it and the first and last grid point
    points: dict[float, int | None] = dict.fromkeys(corners)
    near = {first, final}.union(*({k, k + 1} for k in
                                  (_grid_count(c, sample_period, last) for c in corners)))
    points.update((float(k) * sample_period, k) for k in near if first <= k <= final)
    times = sorted(points)
    kept = 1                                               # the last point is always kept
    for a, b in zip(times, times[1:]):
        ka, kb = points[a], points[b]
        if ka is not None and kb is not None and kb > ka + 1:     # a run of grid points
            kept += _spaced_grid_gaps(ka, kb, sample_period)
        else:
            kept += b - a > _RESOLUTION
    return kept


def _grid_count(value: float, period: float, last: int) -> int:
    """
    Return how many grid times k * period (k = 1..last, as numpy rounds them) are <= value.

    From the estimate value / period, checked against its neighbours, else by bisection.
    """
    guess = min(max(int(value / period), 0), last)
    low, high = max(guess - 2, 0), min(guess + 2, last)
    if low > 0 and float(low) * period > value:
        low = 0
    if high < last and float(high + 1) * period <= value:
        high = last
    while low < high:                       # the largest k in [low, high] with k * period <= value
        mid = (low + high + 1) // 2
        low, high = (mid, high) if float(mid) * period <= value else (low, mid - 1)
    return low


def _spaced_grid_gaps(first: int, last: int, period: float) -> int:
    """Return how many gaps between the grid times first..last exceed the merging microsecond."""
    # each gap is the period within a rounding error of the larger time
    rounding = 2.0 ** -50 * last * period
    if period - _RESOLUTION > rounding:
        return last - first
    if _RESOLUTION - period > rounding:
        return 0
    count, chunk = 0, 1 << 16
    for k in range(first, last, chunk):
        times = np.arange(k, min(k + chunk, last) + 1) * period
        count += int(np.count_nonzero(np.diff(times) > _RESOLUTION))
    return count
