# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
joint_trajectory_controller's sampling of a JointTrajectory, reproduced in numpy for the tests.

Reproduced from ros2_controllers, branch ``jazzy`` at commit
``ed360c97d6e9e74cb884e3e39a949d987cd15c11`` (``JTC_BRANCH``, ``JTC_COMMIT``):
``joint_trajectory_controller/src/trajectory.cpp`` (``Trajectory::sample``,
``Trajectory::set_point_before_trajectory_msg``, ``wraparound_joint``,
``Trajectory::interpolate_between_points``, ``Trajectory::deduce_from_derivatives``) and
``joint_trajectory_controller/src/joint_trajectory_controller.cpp``
(``JointTrajectoryController::validate_trajectory_msg``). Its rules:

* Times are whole nanoseconds (``rclcpp::Time``, ``rclcpp::Duration``); a duration in seconds is
  ``ns / 1e9`` (rclcpp's ``seconds()`` converts through ``std::chrono::duration<double>``,
  which divides by 1e9). A zero ``header.stamp`` starts the trajectory at the controller's first
  sample of it, which in closed loop is the time of the state it starts from.
* The first segment runs from the state before the message (its time, positions and the
  velocities / accelerations it has; if it lacks them and the first point carries them, they
  are zeros) to the first point; the other segments run between consecutive points.
* A segment is linear unless BOTH its ends carry velocities (cubic) or velocities and
  accelerations (quintic). Ends that carry accelerations but not velocities match no branch of
  ``interpolate_between_points``: the controller then commands zeros (``NONE`` below).
* From the last point's time on, the controller commands the last point as it is carried (a
  velocity or acceleration it leaves empty is zero).

Scope: the default ``interpolation_method`` ("splines"); the message's joints already in the
controller's order (``sort_to_local_joint_order``, ``fill_partial_goal`` not reproduced);
effort is not sampled; arithmetic as an x86-64 build does it (IEEE double, no fused
multiply-add), in the C++'s operation order, so the numbers are the controller's bit for bit.

Messages are in the JSON form of ``Trajectory.to_dict``: ``{"joint_names": [...], "points":
[{"time_from_start": s, "positions": [...], "velocities": [...], "accelerations": [...]}]}``,
``time_from_start`` being whole nanoseconds in seconds, an empty list (or a missing key) for a
field a point leaves empty. A state is ``{"positions": [...]}`` with optional "velocities" and
"accelerations". Times of the controller's clock are integers (ns); ``to_ns`` converts.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, Mapping, Sequence

import numpy as np

__all__ = ['BEFORE_FIRST_POINT', 'BEFORE_STATE', 'CUBIC', 'ControllerTrajectory', 'JTC_BRANCH',
           'JTC_COMMIT', 'LINEAR', 'NONE', 'QUINTIC', 'Samples', 'Segment', 'message_dict',
           'sample', 'to_ns', 'validate_trajectory_msg']

JTC_BRANCH = 'jazzy'
JTC_COMMIT = 'ed360c97d6e9e74cb884e3e39a949d987cd15c11'

LINEAR = 'linear'
CUBIC = 'cubic'
QUINTIC = 'quintic'
NONE = 'none'                   # accelerations without velocities: the controller commands 0
#: ``Samples.segment`` of the segment from the state before the message to its first point.
BEFORE_FIRST_POINT = -1
#: ``Samples.segment`` of a time before the state's: sample returns false.
BEFORE_STATE = -2
#: ``std::numeric_limits<float>::epsilon()``, validate_trajectory_msg's "zero" end velocity.
FLOAT_EPSILON = float(np.finfo(np.float32).eps)


def to_ns(seconds: float) -> int:
    """Return whole nanoseconds of a time in seconds that was whole nanoseconds / 1e9."""
    return int(round(seconds * 1e9))


def _seconds(ns: np.ndarray | int) -> np.ndarray | float:
    """Return rclcpp's ``Duration::seconds()``: the nanoseconds divided by 1e9."""
    return np.asarray(ns, dtype=np.int64).astype(float) / 1e9


@dataclass
class _Point:
    """A JointTrajectoryPoint; mutable as in C++, where deduce_from_derivatives fills it in."""

    ns: int
    positions: list[float]
    velocities: list[float]
    accelerations: list[float]

    @classmethod
    def parse(cls, point: Mapping[str, Any], ns: int = 0) -> _Point:
        """Return a point (or state) of the JSON form, its fields copied."""
        fields = [[float(v) for v in point.get(name) or ()]
                  for name in ('positions', 'velocities', 'accelerations')]
        return cls(ns, *fields)


def message_dict(msg: Any) -> dict[str, Any]:
    """
    Return a trajectory_msgs/JointTrajectory (any object with its fields) in the JSON form.

    ``time_from_start`` becomes the point's whole nanoseconds / 1e9; every field as carried.
    """
    points = []
    for point in msg.points:
        ns = int(point.time_from_start.sec) * 1_000_000_000 + int(point.time_from_start.nanosec)
        points.append({'time_from_start': ns / 1e9,
                       'positions': [float(v) for v in point.positions],
                       'velocities': [float(v) for v in point.velocities],
                       'accelerations': [float(v) for v in point.accelerations]})
    return {'joint_names': list(msg.joint_names), 'points': points}


def _normalize_angle(angle: float) -> float:
    """Return ``angles::normalize_angle`` (ros/angles, angles.h): the angle in (-pi, pi]."""
    result = math.fmod(angle + math.pi, 2.0 * math.pi)
    if result <= 0.0:
        return result + math.pi
    return result - math.pi


def _wraparound_joint(current: list[float], following: list[float],
                      wraparound: Sequence[bool]) -> None:
    """Reproduce ``wraparound_joint``: move a continuous joint's state next to the first point."""
    for i, wraps in enumerate(wraparound):
        if wraps:
            dist = _normalize_angle(following[i] - current[i])   # shortest_angular_distance
            if abs(abs(dist) - math.pi) < 1e-9:
                dist = abs(dist) if following[i] > current[i] else -abs(dist)
            current[i] = following[i] - dist


def _deduce_from_derivatives(first: _Point, second: _Point, dim: int, delta_t: float) -> None:
    """Reproduce ``Trajectory::deduce_from_derivatives`` (integrate a point without positions)."""
    if second.positions:
        return
    if not first.velocities:
        first.velocities = [0.0] * dim
    if not second.velocities:
        if not first.accelerations:
            first.accelerations = [0.0] * dim
        # C++ reads second_state.accelerations[i] here: it must carry them (integration mode)
        second.velocities = [first.velocities[i]
                             + (first.accelerations[i] + second.accelerations[i]) * 0.5 * delta_t
                             for i in range(dim)]
    second.positions = [first.positions[i]
                        + (first.velocities[i] + second.velocities[i]) * 0.5 * delta_t
                        for i in range(dim)]


def _kind(a: _Point, b: _Point) -> str:
    """Return the interpolation ``interpolate_between_points`` chooses for ends a and b."""
    has_velocity = bool(a.velocities) and bool(b.velocities)
    has_accel = bool(a.accelerations) and bool(b.accelerations)
    if not has_velocity and not has_accel:
        return LINEAR
    if has_velocity:
        return QUINTIC if has_accel else CUBIC
    return NONE


def _coefficients(kind: str, a: _Point, b: _Point, dim: int, duration_ns: int) -> np.ndarray:
    """Return the position polynomial (dim, 6), lowest power first, as the C++ computes it."""
    c = np.zeros((dim, 6))
    if kind == NONE:
        return c
    sp, ep = np.array(a.positions), np.array(b.positions)
    duration = float(_seconds(duration_ns))
    c[:, 0] = sp
    if kind == LINEAR:
        if duration != 0.0:
            c[:, 1] = (ep - sp) / duration
        return c
    T = [1.0]                                    # generate_powers(5, duration, T)
    for _ in range(5):
        T.append(T[-1] * duration)
    sv, ev = np.array(a.velocities), np.array(b.velocities)
    c[:, 1] = sv
    if kind == CUBIC:
        if duration != 0.0:
            c[:, 2] = (-3.0 * sp + 3.0 * ep - 2.0 * sv * T[1] - ev * T[1]) / T[2]
            c[:, 3] = (2.0 * sp - 2.0 * ep + sv * T[1] + ev * T[1]) / T[3]
        return c
    sa, ea = np.array(a.accelerations), np.array(b.accelerations)
    c[:, 2] = 0.5 * sa
    if duration != 0.0:
        c[:, 3] = (-20.0 * sp + 20.0 * ep - 3.0 * sa * T[2] + ea * T[2] - 12.0 * sv * T[1]
                   - 8.0 * ev * T[1]) / (2.0 * T[3])
        c[:, 4] = (30.0 * sp - 30.0 * ep + 3.0 * sa * T[2] - 2.0 * ea * T[2] + 16.0 * sv * T[1]
                   + 14.0 * ev * T[1]) / (2.0 * T[4])
        c[:, 5] = (-12.0 * sp + 12.0 * ep - sa * T[2] + ea * T[2] - 6.0 * sv * T[1]
                   - 6.0 * ev * T[1]) / (2.0 * T[5])
    return c


def _evaluate(kind: str, c: np.ndarray, s: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return positions, velocities, accelerations (m, dim) at s (m,) s into the segment."""
    t = [np.ones_like(s)[:, None]]               # generate_powers(5, duration_so_far, t)
    for _ in range(5):
        t.append(t[-1] * s[:, None])
    c = [c[None, :, k] for k in range(6)]
    zeros = np.zeros((s.size, c[0].shape[1]))
    if kind == NONE:
        return zeros, zeros.copy(), zeros.copy()
    if kind == LINEAR:
        return t[0] * c[0] + t[1] * c[1], t[0] * c[1], zeros
    if kind == CUBIC:
        return (t[0] * c[0] + t[1] * c[1] + t[2] * c[2] + t[3] * c[3],
                t[0] * c[1] + t[1] * 2.0 * c[2] + t[2] * 3.0 * c[3],
                t[0] * 2.0 * c[2] + t[1] * 6.0 * c[3])
    return (t[0] * c[0] + t[1] * c[1] + t[2] * c[2] + t[3] * c[3] + t[4] * c[4] + t[5] * c[5],
            t[0] * c[1] + t[1] * 2.0 * c[2] + t[2] * 3.0 * c[3] + t[3] * 4.0 * c[4]
            + t[4] * 5.0 * c[5],
            t[0] * 2.0 * c[2] + t[1] * 6.0 * c[3] + t[2] * 12.0 * c[4] + t[3] * 20.0 * c[5])


@dataclass(frozen=True)
class Segment:
    """
    One segment as ``interpolate_between_points`` interpolates it, [t0_ns, t1_ns).

    ``index`` is ``BEFORE_FIRST_POINT`` for the segment from the state to the first point, else
    i for points i -> i + 1. ``coefficients`` (n_joints, 6) is the position polynomial in s,
    the seconds since t0, lowest power first; powers the kind does not use are zero.
    """

    index: int
    t0_ns: int
    t1_ns: int
    kind: str
    coefficients: np.ndarray

    @property
    def duration(self) -> float:
        """Return the segment's length in seconds, as the controller computes it."""
        return float(_seconds(self.t1_ns - self.t0_ns))

    def evaluate(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return positions, velocities, accelerations (m, n_joints) at s (m,) seconds in."""
        return _evaluate(self.kind, self.coefficients, np.asarray(s, dtype=float).ravel())

    def max_abs_jerk(self) -> np.ndarray:
        """
        Return each joint's largest |jerk| inside the segment (rad/s^3, (n_joints,)).

        Jerk is 6 c3 + 24 c4 s + 60 c5 s^2: zero on a linear segment (whose velocity steps at
        its ends are not counted), constant on a cubic, extreme at an end or the vertex on a
        quintic.
        """
        c = self.coefficients
        ends = np.array([0.0, self.duration])
        jerk = 6.0 * c[:, 3:4] + 24.0 * c[:, 4:5] * ends + 60.0 * c[:, 5:6] * ends ** 2
        peak = np.max(np.abs(jerk), axis=1)
        with np.errstate(divide='ignore', invalid='ignore'):
            vertex = -24.0 * c[:, 4] / (120.0 * c[:, 5])      # where the snap is zero
            at_vertex = np.abs(6.0 * c[:, 3] + 24.0 * c[:, 4] * vertex
                               + 60.0 * c[:, 5] * vertex ** 2)
        inside = (c[:, 5] != 0.0) & (vertex > 0.0) & (vertex < self.duration)
        return np.where(inside, np.maximum(peak, at_vertex), peak)


@dataclass(frozen=True)
class Samples:
    """
    What ``Trajectory::sample`` outputs at each sample time.

    ``valid`` is sample's return value (False before the state's time, or holding a last point
    without positions); invalid rows are NaN. ``segment`` is the segment's ``Segment.index``,
    the last point's index from its time on (the controller holds it), or ``BEFORE_STATE``.
    """

    times_ns: np.ndarray        # (m,) int64
    valid: np.ndarray           # (m,) bool
    segment: np.ndarray         # (m,) int
    positions: np.ndarray       # (m, n_joints)
    velocities: np.ndarray      # (m, n_joints)
    accelerations: np.ndarray   # (m, n_joints)


class ControllerTrajectory:
    """
    A message as joint_trajectory_controller's ``Trajectory`` holds and samples it.

    Built from the message (JSON form) and the state before it: ``set_point_before_trajectory_msg``
    at ``state_time_ns``; ``angle_wraparound`` flags the continuous joints (the controller sets
    them from the URDF). The trajectory starts at ``header_stamp_ns`` or, when that is zero,
    at the controller's first sample, ``first_sample_ns`` (default the state's time, as in
    closed loop, where the controller takes the state and samples at the same update).

    ``deduce_from_derivatives`` fills in points without positions as the controller samples
    them, so the times of one ``sample`` call must not decrease (the controller's go forward,
    and then its search from the last segment it used finds the segment a search from the first
    finds).
    """

    def __init__(self, msg: Mapping[str, Any], state: Mapping[str, Any], *,
                 state_time_ns: int = 0, header_stamp_ns: int = 0,
                 first_sample_ns: int | None = None,
                 angle_wraparound: Sequence[bool] = ()) -> None:
        self.joint_names = list(msg['joint_names'])
        self.points = [_Point.parse(p, to_ns(float(p['time_from_start'])))
                       for p in msg['points']]
        self.state_time_ns = int(state_time_ns)
        if header_stamp_ns != 0:
            self.start_ns = int(header_stamp_ns)
        else:
            self.start_ns = self.state_time_ns if first_sample_ns is None else first_sample_ns
        self.state = _Point.parse(state)                # set_point_before_trajectory_msg
        if not self.points:
            return
        first = self.points[0]
        if not self.state.velocities and first.velocities:
            self.state.velocities = [0.0] * len(first.velocities)
        if not self.state.accelerations and first.accelerations:
            self.state.accelerations = [0.0] * len(first.accelerations)
        _wraparound_joint(self.state.positions, first.positions, angle_wraparound)

    @property
    def dim(self) -> int:
        """Return the number of joints (the state's positions, as the C++ takes it)."""
        return len(self.state.positions)

    @property
    def end_ns(self) -> int:
        """Return the last point's time on the controller's clock (ns)."""
        return self.start_ns + self.points[-1].ns

    def _ends(self, index: int) -> tuple[_Point, _Point, int, int]:
        """Return a segment's end points and times (ns), deducing as ``sample`` does first."""
        if index == BEFORE_FIRST_POINT:
            a, b = self.state, self.points[0]
            t0, t1 = self.state_time_ns, self.start_ns + b.ns
        else:
            a, b = self.points[index], self.points[index + 1]
            t0, t1 = self.start_ns + a.ns, self.start_ns + b.ns
        _deduce_from_derivatives(a, b, self.dim, float(_seconds(t1 - t0)))
        return a, b, t0, t1

    def segment(self, index: int) -> Segment:
        """Return segment ``index`` (``BEFORE_FIRST_POINT`` or i), deducing it if need be."""
        a, b, t0, t1 = self._ends(index)
        kind = _kind(a, b)
        return Segment(index, t0, t1, kind, _coefficients(kind, a, b, self.dim, t1 - t0))

    def segments(self) -> list[Segment]:
        """Return every segment the controller passes through, in order (deducing them all)."""
        first = [BEFORE_FIRST_POINT] if self.start_ns + self.points[0].ns > self.state_time_ns \
            else []
        return [self.segment(i) for i in first + list(range(len(self.points) - 1))]

    def _locate(self, times: np.ndarray) -> np.ndarray:
        """Return each time's segment index, the last point's past the end, or BEFORE_STATE."""
        last = len(self.points) - 1
        found = np.full(times.size, last)
        found[times < self.start_ns + self.points[0].ns] = BEFORE_FIRST_POINT
        found[times < self.state_time_ns] = BEFORE_STATE
        open_ = found == last
        for i in range(last):                    # sample's loop: the first segment that holds t
            t0, t1 = self.start_ns + self.points[i].ns, self.start_ns + self.points[i + 1].ns
            hit = open_ & (times >= t0) & (times < t1)
            found[hit] = i
            open_ &= ~hit
        return found

    def sample(self, times_ns: Sequence[int] | np.ndarray) -> Samples:
        """Reproduce ``Trajectory::sample`` (splines) at each time (ns, not decreasing)."""
        times = np.asarray(times_ns, dtype=np.int64).ravel()
        if np.any(np.diff(times) < 0):
            raise ValueError('the controller samples at times that never decrease')
        out = np.full((3, times.size, self.dim), np.nan)
        valid = np.zeros(times.size, dtype=bool)
        if not self.points:
            return Samples(times, valid, np.full(times.size, BEFORE_STATE), *out)
        found = self._locate(times)
        last = len(self.points) - 1
        for index in dict.fromkeys(found.tolist()):          # in the order sampled
            rows = found == index
            if index == last:
                valid[rows] = self._hold(rows, out)
            elif index != BEFORE_STATE:
                a, b, t0, t1 = self._ends(index)
                out[:, rows] = self._interpolate(a, b, t0, t1, times[rows])
                valid[rows] = True
        return Samples(times, valid, found, *out)

    def _hold(self, rows: np.ndarray, out: np.ndarray) -> bool:
        """Reproduce sample's "whole animation has played out": command the last point."""
        last = len(self.points) - 1
        final = self.points[last]
        if not final.positions and last > 0 and self.points[last - 1].positions:
            self._ends(last - 1)                 # #2282: deduce the last point after all
        if not final.positions:
            return False                         # sample returns false
        zeros = [0.0] * len(final.positions)
        for k, values in enumerate((final.positions, final.velocities or zeros,
                                    final.accelerations or zeros)):
            out[k, rows] = values
        return True

    def _interpolate(self, a: _Point, b: _Point, t0: int, t1: int, times: np.ndarray
                     ) -> np.ndarray:
        """Reproduce ``interpolate_between_points`` at times (ns): (3, m, dim)."""
        so_far = times - t0
        between = t1 - t0
        kind = _kind(a, b)
        clamped = (so_far < 0) | (so_far > between)   # seconds() is monotone in ns
        so_far = np.clip(so_far, 0, between)
        coefficients = _coefficients(kind, a, b, self.dim, between)
        result = np.stack(_evaluate(kind, coefficients, _seconds(so_far)))
        if np.any(clamped):                      # has_velocity = has_accel = false: linear
            linear = _coefficients(LINEAR, a, b, self.dim, between)
            result[:, clamped] = np.stack(_evaluate(LINEAR, linear, _seconds(so_far[clamped])))
        return result


def sample(msg: Mapping[str, Any], state: Mapping[str, Any],
           times_ns: Sequence[int] | np.ndarray, **options: Any) -> Samples:
    """
    Return what the controller commands at ``times_ns`` (not decreasing) for ``msg``.

    ``state`` is the state before the message; ``options`` as for ``ControllerTrajectory``.
    """
    return ControllerTrajectory(msg, state, **options).sample(times_ns)


def validate_trajectory_msg(msg: Mapping[str, Any], *, joints: Sequence[str] | None = None,
                            header_stamp_ns: int = 0, now_ns: int = 0,
                            allow_partial_joints_goal: bool = False,
                            allow_nonzero_velocity_at_trajectory_end: bool = False,
                            allow_integration_in_goal_trajectories: bool = False,
                            has_effort_command_interface: bool = False) -> str | None:
    """
    Reproduce ``JointTrajectoryController::validate_trajectory_msg``: the reason, or None.

    ``joints`` are the controller's joints (default: the message's); the flags are the
    controller's parameters, at their defaults; ``now_ns`` is the controller's clock, for a
    message whose stamp is not zero.
    """
    names = list(msg.get('joint_names') or ())
    points = list(msg.get('points') or ())
    joints = names if joints is None else list(joints)
    if not allow_partial_joints_goal and len(names) != len(joints):
        return "joints on incoming trajectory don't match the controller joints"
    if not names:
        return 'empty joint names on incoming trajectory'
    if not points:
        return 'empty trajectory received'
    for name in names:
        if name not in joints:
            return f"incoming joint {name} doesn't match the controller's joints"
    if not allow_nonzero_velocity_at_trajectory_end:
        for i, v in enumerate(points[-1].get('velocities') or ()):
            if abs(v) > FLOAT_EPSILON:
                return f'velocity of last trajectory point of joint {names[i]} is not zero: {v}'
    if header_stamp_ns != 0 and header_stamp_ns + to_ns(points[-1]['time_from_start']) < now_ns:
        return 'received trajectory with non-zero start time that ends in the past'
    previous_ns = 0
    for i, point in enumerate(points):
        ns = to_ns(float(point['time_from_start']))
        if i > 0 and ns <= previous_ns:
            return f'time between points {i - 1} and {i} is not strictly increasing'
        previous_ns = ns
        fields = {name: list(point.get(name) or ())
                  for name in ('positions', 'velocities', 'accelerations', 'effort')}
        if allow_integration_in_goal_trajectories:
            if not (fields['positions'] or fields['velocities'] or fields['accelerations']):
                return 'the given trajectory has no position, velocity, or acceleration points'
            allow_empty = {'positions': True, 'velocities': True, 'accelerations': True}
        else:
            allow_empty = {'positions': False, 'velocities': True, 'accelerations': True}
        for name, empty_ok in allow_empty.items():
            if not (empty_ok and not fields[name]) and len(fields[name]) != len(names):
                return (f'mismatch between joint_names size ({len(names)}) and {name} '
                        f'({len(fields[name])}) at point #{i}')
        if not has_effort_command_interface and fields['effort']:
            return ('trajectories with effort fields are only supported for controllers using '
                    "the 'effort' command interface")
    return None
