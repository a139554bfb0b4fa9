# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The joint trajectory a controller gets: the paper's servo motion, or a profile's.

Under the servo law (``servo_trajectory``) every joint turns at one fixed angular velocity.

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

Under a trapezoidal or jerk-limited profile (``motion_trajectory``; ``motion_profile``) points
carry velocities, and accelerations for the jerk-limited one, at every phase boundary, so that
the controller's cubics or quintics are the profile itself (see ``motion_trajectory``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from trajplan_ros.motion.motion_profile import Timing
from trajplan_ros.motion.rest_to_rest import (GAP_NS, joint_profiles, JointProfiles,
                                              SMALLEST_TURN)
from trajplan_ros.motion.time_law import JERK_LIMITED, SERVO, TimeLaw

__all__ = ['Trajectory', 'motion_points', 'motion_states', 'motion_trajectory', 'path_points',
           'path_trajectory', 'servo_trajectory', 'trajectory_points']

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

    def at_time(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        Return positions, velocities and accelerations at times t (s), each (len(t), n_joints).

        Exact for every law, as Ruckig's ``at_time``: between two points the polynomial that
        joint_trajectory_controller fits through what they carry, from the start at rest:
        linear through positions alone (the servo motion), cubic with velocities (a
        trapezoidal phase is a parabola), quintic with accelerations (a jerk-limited phase is
        a cubic); every phase boundary is a point. Before 0 the start, after the end the last
        point, at rest.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        n = len(self.start)
        times = np.concatenate(([0.0], self.times))
        rest = np.zeros((1, n))
        q = np.vstack((self.start, self.positions))
        v = None if self.velocities is None else np.vstack((rest, self.velocities))
        a = None if self.accelerations is None else np.vstack((rest, self.accelerations))
        k = np.clip(np.searchsorted(times, t, side='right') - 1, 0, len(times) - 2)
        h = (times[k + 1] - times[k])[:, None]
        x = (np.clip(t, 0.0, self.duration) - times[k])[:, None]
        coefficients = _segment_polynomials(q[k], q[k + 1], h,
                                            None if v is None else (v[k], v[k + 1]),
                                            None if a is None else (a[k], a[k + 1]))
        position = sum(c * x ** p for p, c in enumerate(coefficients))
        velocity = sum(p * c * x ** (p - 1) for p, c in enumerate(coefficients) if p > 0)
        acceleration = sum(p * (p - 1) * c * x ** (p - 2)
                           for p, c in enumerate(coefficients) if p > 1)
        moving = ((t >= 0.0) & (t < self.duration))[:, None]
        position = np.where((t >= self.duration)[:, None], self.positions[-1], position)
        return (np.where((t <= 0.0)[:, None], self.start, position),
                np.where(moving, velocity, 0.0),
                np.where(moving, acceleration, 0.0) if len(coefficients) > 2
                else np.zeros_like(position))

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


def _segment_polynomials(q0: np.ndarray, q1: np.ndarray, h: np.ndarray,
                         velocities: tuple[np.ndarray, np.ndarray] | None,
                         accelerations: tuple[np.ndarray, np.ndarray] | None
                         ) -> list[np.ndarray]:
    """
    Return the coefficients c_0, c_1, ... of each segment's polynomial in its own time, (S, n).

    Linear, cubic or quintic Hermite interpolation of the ends' positions, velocities and
    accelerations over the segment's duration h (S, 1), as joint_trajectory_controller fits.
    """
    d = q1 - q0
    if velocities is None:
        return [q0, d / h]
    v0, v1 = velocities
    if accelerations is None:
        return [q0, v0, (3.0 * d - (2.0 * v0 + v1) * h) / h ** 2,
                (-2.0 * d + (v0 + v1) * h) / h ** 3]
    a0, a1 = accelerations
    return [q0, v0, 0.5 * a0,
            (20.0 * d - (8.0 * v1 + 12.0 * v0) * h - (3.0 * a0 - a1) * h ** 2) / (2.0 * h ** 3),
            (-30.0 * d + (14.0 * v1 + 16.0 * v0) * h + (3.0 * a0 - 2.0 * a1) * h ** 2)
            / (2.0 * h ** 4),
            (12.0 * d - 6.0 * (v1 + v0) * h - (a0 - a1) * h ** 2) / (2.0 * h ** 5)]


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
    positions = _servo_positions(start, goal, omega, arrive, t)
    positions[-1] = goal                         # its time is at least R (up to its rounding)
    return Trajectory(tuple(names), start, t, positions)


def _servo_positions(start: np.ndarray, goal: np.ndarray, omega: float | np.ndarray,
                     arrive: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Return the servo motion's positions (T, n) at times t (T,): at omega till ``arrive``."""
    turned = np.sign(goal - start) * omega * t[:, None]
    return np.where(t[:, None] >= arrive[None, :], goal, start + turned)


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


def motion_trajectory(start: np.ndarray, goal: np.ndarray, law: TimeLaw, timing: Timing, *,
                      sample_period: float = 0.1,
                      joint_names: tuple[str, ...] | None = None) -> Trajectory:
    """
    Return the motion from ``start`` to ``goal`` under every joint's time ``law`` and ``timing``.

    Servo: ``servo_trajectory`` at each joint's velocity, or (synchronized) at the velocity that
    brings it to the goal at the end, a straight line. Trapezoidal and jerk-limited: each
    joint's profile (``rest_to_rest``, its phases whole nanoseconds), with a point at every
    joint's phase boundary and every ``sample_period`` (a sample near a boundary left out:
    ``_profile_times_ns``). Trapezoidal points carry positions and velocities: the
    controller's cubics are then the profile's quadratics; jerk-limited ones also
    accelerations: its quintics are the profile's cubics. The last point, at the end, is at
    rest at the goal.

    Each point's values are the profile's at its time, but a point's position is a double,
    rounded, and a polynomial fitted to rounded ends is off by an acceleration and a jerk that
    grow as its segment shortens. So positions are computed in extended precision
    (``JointProfiles.turn``) and rounded once, to ``_bits`` significant bits, which makes the
    controller's 3 (cubic) or 12, 20 and 30 (quintic) times them exact
    (``_short_mantissas``), and no segment is shorter than ``_segment_ns``, over which that
    rounding keeps within a share of the tolerance: the profiles keep their boundaries that
    far apart (``rest_to_rest._place``), the samples too.
    """
    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    names = joint_names or tuple(f'joint{i + 1}' for i in range(start.size))
    if law.kind == SERVO:
        return servo_trajectory(start, goal, _servo_speeds(start, goal, law, timing),
                                sample_period=sample_period, joint_names=names)
    profiles = _profiles(start, goal, law, timing)
    t_ns = _profile_times_ns(profiles, sample_period)
    # the state at every point: the phase that starts there, for the next segment
    _, velocity, acceleration, _ = profiles.sample(t_ns)
    turn = profiles.turn(t_ns)
    positions = _short_mantissas(start.astype(np.longdouble) + turn, _bits(law)).astype(float)
    positions[-1] = goal
    velocity[-1], acceleration[-1] = 0.0, 0.0
    return Trajectory(tuple(names), start, t_ns / 1e9, positions, velocity,
                      acceleration if law.kind == JERK_LIMITED else None)


def path_trajectory(points: Sequence[np.ndarray], law: TimeLaw, timing: Timing, *,
                    sample_period: float = 0.1,
                    joint_names: tuple[str, ...] | None = None) -> Trajectory:
    """
    Return the motion through ``points`` (the start, via points, the goal), at rest at each.

    Each segment is ``motion_trajectory``'s; a via point is a point of the message with zero
    velocity and acceleration, so the controller stops there as the check assumed.
    """
    segments = [motion_trajectory(a, b, law, timing, sample_period=sample_period,
                                  joint_names=joint_names) for a, b in zip(points, points[1:])]
    if len(segments) == 1:
        return segments[0]
    offsets = np.cumsum([0] + [np.round(s.times[-1] * 1e9) for s in segments[:-1]])
    times = np.concatenate([(np.round(s.times * 1e9) + o) / 1e9
                            for s, o in zip(segments, offsets)])

    def joined(name: str) -> np.ndarray | None:
        parts = [getattr(s, name) for s in segments]
        return None if parts[0] is None else np.vstack(parts)

    return Trajectory(segments[0].joint_names, segments[0].start, times,
                      joined('positions'), joined('velocities'), joined('accelerations'))


def path_points(points: Sequence[np.ndarray], law: TimeLaw, timing: Timing,
                sample_period: float = 0.1) -> int:
    """Return how many points ``path_trajectory`` gives, without building a long one."""
    return sum(motion_points(a, b, law, timing, sample_period)
               for a, b in zip(points, points[1:]))


def motion_points(start: np.ndarray, goal: np.ndarray, law: TimeLaw, timing: Timing,
                  sample_period: float = 0.1) -> int:
    """
    Return how many points ``motion_trajectory`` gives, without building a long one.

    Exact but for a trajectory of more than a million sample periods, where it returns the
    number of periods (fewer than the points: the caller refuses it anyway).
    """
    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    if law.kind == SERVO:
        return trajectory_points(start, goal, _servo_speeds(start, goal, law, timing),
                                 sample_period)
    profiles = _profiles(start, goal, law, timing)
    periods = float(profiles.ends_ns.max(initial=0)) / 1e9 / sample_period
    return int(periods) if periods > 1e6 else len(_profile_times_ns(profiles, sample_period))


def motion_states(start: np.ndarray, goal: np.ndarray, law: TimeLaw, timing: Timing,
                  t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Return the motion's positions, velocities, accelerations and jerks at times t (T,), s.

    Each (T, n_joints), as ``motion_trajectory`` publishes the motion; under the servo law the
    velocity steps at the start and at each arrival (acceleration and jerk are 0 between).
    """
    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    t = np.asarray(t, dtype=float)
    if law.kind == SERVO:
        speed = _servo_speeds(start, goal, law, timing)
        arrive = np.abs(goal - start) / speed
        q = _servo_positions(start, goal, speed, arrive, t)
        moving = t[:, None] < arrive[None, :]
        zero = np.zeros_like(q)
        return q, np.where(moving, np.sign(goal - start) * speed, 0.0), zero, zero
    turn, velocity, acceleration, jerk = _profiles(start, goal, law, timing).sample(
        np.round(t * 1e9).astype(np.int64))
    return start + turn, velocity, acceleration, jerk


def _servo_speeds(start: np.ndarray, goal: np.ndarray, law: TimeLaw,
                  timing: Timing) -> np.ndarray:
    """Return each joint's servo velocity: its own, or (synchronized) d_i / R."""
    if timing is not Timing.SYNCHRONIZED:
        return law.velocity
    d = np.abs(goal - start)
    duration = float(np.max(d / law.velocity, initial=0.0))
    return np.where(d > 0.0, d / duration, law.velocity) if duration > 0.0 else law.velocity


def _profiles(start: np.ndarray, goal: np.ndarray, law: TimeLaw, timing: Timing
              ) -> JointProfiles:
    """Return each joint's profile, stretched to the slowest joint's end if synchronized."""
    if start.shape != goal.shape or start.ndim != 1 or law.velocity.shape != start.shape:
        raise ValueError('start, goal and the time law must be of the same joints')
    gap_ns, first_ns = _segment_ns(start, goal, law)
    return joint_profiles(goal - start, law.velocity, law.acceleration, law.jerk,
                          synchronized=timing is Timing.SYNCHRONIZED, gap_ns=gap_ns,
                          first_ns=first_ns)


#: Significant bits of a published profile position: the controller's 3 times it (cubic), or
#: 12, 20 and 30 times it (quintic), are then exact.
_CUBIC_BITS = 51
_QUINTIC_BITS = 49
#: The share of the tolerance under the controller (relative to a limit) that the rounding of
#: the positions may take; the controller's other roundings take less than 1e-7 of the rest.
_ACCELERATION_SHARE = 0.75e-6
_JERK_SHARE = 0.75e-3
#: The most a position computed by ``JointProfiles.turn`` is off, in its type's last bits.
_WORK_ULPS = 16


def _bits(law: TimeLaw) -> int:
    """Return the significant bits of a position published under ``law``."""
    return _QUINTIC_BITS if law.kind == JERK_LIMITED else _CUBIC_BITS


def _segment_ns(start: np.ndarray, goal: np.ndarray, law: TimeLaw) -> tuple[int, int]:
    """
    Return the shortest segment (ns) whose polynomial the positions' rounding keeps in limits.

    And the shortest first segment. A position rounded to ``_bits`` is off by at most e, half
    its last bit (the largest where the joint turns: between start and goal). The
    controller's polynomial over T seconds through two such ends is off by e (3 s^2 - 2 s^3)
    (cubic) or e (10 s^3 - 15 s^4 + 6 s^5) (quintic) per end, s = t / T: its acceleration by
    at most 12 e / T^2 and its jerk by 120 e / T^3. So T must be at least
    sqrt(12 e / (share a)) and cbrt(120 e / (share j)) for every moving joint, and
    ``GAP_NS``. The first segment starts at the state, whose position has 53 bits: the
    quintic's 12, 20 and 30 times it are rounded, by up to e, 2 e and 2 e, so its
    acceleration is off by up to 34 e / T^2 (its jerk still 120 e / T^3; the last segment's
    errors, from the goal's, grow as the profile's acceleration falls to zero). e also holds
    ``_WORK_ULPS`` last bits of ``np.longdouble``, in which the positions are computed: where
    that is no wider than a double, their own rounding is that large.
    """
    turn = np.abs(goal - start)
    _, exponent = np.frexp(np.maximum(np.abs(start), np.abs(goal)))
    work = _WORK_ULPS * np.ldexp(1.0, exponent - 1 - np.finfo(np.longdouble).nmant)
    e = (np.ldexp(1.0, exponent - _bits(law) - 1) + work)[turn > SMALLEST_TURN]
    a, j = law.acceleration[turn > SMALLEST_TURN], law.jerk[turn > SMALLEST_TURN]
    first = 34.0 if law.kind == JERK_LIMITED else 12.0
    with np.errstate(divide='ignore'):
        jerk = np.cbrt(120.0 * e / (_JERK_SHARE * j))
        seconds = [np.max(np.maximum(np.sqrt(k * e / (_ACCELERATION_SHARE * a)), jerk),
                          initial=0.0) for k in (12.0, first)]
    return tuple(max(GAP_NS, int(np.ceil(x * 1e9))) for x in seconds)


#: The least time (ns) between a sample and a phase boundary: a sample closer is left out.
_SAMPLE_GAP = 1_000_000


def _profile_times_ns(profiles: JointProfiles, sample_period: float) -> np.ndarray:
    """
    Return the points' times (ns): every phase boundary and samples apart from them.

    The samples every ``sample_period`` (every few periods if one is shorter than the gap
    between boundaries), each at least ``_SAMPLE_GAP`` (or a quarter period, if shorter) and
    the gap from every boundary, none before the first boundary's least time.
    """
    if not (np.isfinite(sample_period) and sample_period > 0):
        raise ValueError('sample_period must be finite and positive')
    period_ns = sample_period * 1e9
    end = int(profiles.ends_ns.max(initial=0))
    if end == 0:
        return np.array([max(int(round(period_ns)), 1)], dtype=np.int64)
    corners = profiles.boundaries_ns
    stride = max(int(np.ceil(profiles.gap_ns / period_ns)), 1)
    count = int(end // period_ns) // stride
    grid = np.round(np.arange(1, count + 1) * stride * period_ns).astype(np.int64)
    near = np.searchsorted(corners, grid)
    gap = np.minimum(np.abs(grid - corners[np.minimum(near, corners.size - 1)]),
                     np.abs(grid - corners[np.maximum(near - 1, 0)]))
    least = max(min(_SAMPLE_GAP, period_ns / 4), profiles.gap_ns)
    keep = grid[(gap >= least) & (grid >= profiles.first_ns) & (grid < end)]
    return np.union1d(keep, corners)


def _short_mantissas(values: np.ndarray, bits: int) -> np.ndarray:
    """Return ``values`` rounded to ``bits`` significant bits."""
    fraction, exponent = np.frexp(values)
    return np.ldexp(np.round(np.ldexp(fraction, bits)), exponent - bits)
