# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Each joint's rest-to-rest profile under velocity, acceleration and jerk limits, in seven phases.

A joint turning by d >= 0 rad from rest to rest, with limits v, a, j (j = inf for the
trapezoidal profile), rises to a peak velocity v_p <= v, cruises, and falls back. With the peak
acceleration a_p = a if v_p j >= a^2, else sqrt(v_p j), the phases are

    jerk +j for a_p / j,  0 for v_p / a_p - a_p / j,  -j for a_p / j,   (the rise, T_a / 2)
    cruise at v_p for d / v_p - T_a,
    jerk -j, 0, +j for the same times as the rise,

with T_a = v_p / a + a / j (or 2 sqrt(v_p / j)) as in ``time_law``, so the duration is
d / v_p + T_a. The fastest profile (``time_law.joint_time``) takes v_p = min(v, the peak
without cruise); a profile stretched to a longer duration (time synchronisation) takes the
lower v_p that solves d / v_p + T_a(v_p) = T (that duration decreases with v_p up to the peak
without cruise), keeping a and j. Under the trapezoidal profile the jerk phases last 0.

Whole nanoseconds: a JointTrajectory message times its points in whole nanoseconds, and
joint_trajectory_controller fits one polynomial per segment between points, exact only if no
phase boundary falls inside. So every phase lasts a whole number of nanoseconds: each rise
phase is rounded up, the cruise fills the duration (rounded up, or the common end when
synchronized), and v_p, a_p and j are then recomputed from d for those times. Every phase is
at least as long as before, so the limits still hold (a stretched profile is first solved
for 8 ns less than its end, the most the rounding can add). With the rules of
``joint_profiles`` (a common end ``SLACK_NS`` after the slowest joint's fastest, phases under
``SHORTEST_NS`` folded into others) the duration grows by at most about 0.8 µs.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ['GAP_NS', 'JointProfiles', 'SLACK_NS', 'SMALLEST_TURN', 'SNAP_NS', 'advance',
           'joint_profiles']

#: Bisection steps for a stretched profile's peak velocity: to the last bit of a double.
_BISECTION = 200
#: Nanoseconds per second; the most the rounding of the phases to them adds to a duration.
_NS = 1e9
_ROUNDING_NS = 8
#: Without synchronisation, a joint that would arrive less than this (ns) before the last one
#: arrives with it: two arrivals closer than that would make a segment too short for the
#: controller's polynomials to be computed exactly (see ``trajectory.motion_trajectory``).
SNAP_NS = 1e6
#: The shortest phase (ns) but zero, and how much later than the fastest a common end is (ns).
SHORTEST_NS = 100.0
SLACK_NS = 500.0
#: A turn (rad) up to this is none: the joint stays at its start until the last point.
SMALLEST_TURN = 1e-12
#: The least time (ns) between two phase boundaries that are not one (``_dodge``).
GAP_NS = 500_000


def _whole_ns(seconds: np.ndarray) -> np.ndarray:
    """Return ``seconds`` in nanoseconds rounded up, but for rounding errors below 1e-6 ns."""
    return np.ceil(np.round(seconds * _NS, 6))


def advance(tau: np.ndarray, pos: np.ndarray, vel: np.ndarray, acc: np.ndarray,
            jerk: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return position, velocity and acceleration tau s into a piece of constant jerk."""
    return (pos + tau * (vel + tau * (acc / 2.0 + tau * jerk / 6.0)),
            vel + tau * (acc + tau * jerk / 2.0), acc + tau * jerk)


def _ramp(vp: np.ndarray, a: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Return T_a (s): the time to reach vp from rest and back, at most a and j (see module)."""
    with np.errstate(divide='ignore', invalid='ignore'):
        return np.where(vp * j >= a * a, vp / a + a / j, 2.0 * np.sqrt(vp / j))


def _peak_without_cruise(d: np.ndarray, a: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Return the peak velocity of the fastest profile over d with no cruise: v_p T_a = d."""
    with np.errstate(divide='ignore', invalid='ignore'):
        rising = 0.5 * a * (np.sqrt((a / j) ** 2 + 4.0 * d / a) - a / j)   # a_p = a
        short = np.cbrt(d * d * j / 4.0)                                     # a_p < a
    return np.where(d >= 2.0 * a ** 3 / (j * j), rising, short)


def _stretched_peak(d: np.ndarray, duration: np.ndarray, top: np.ndarray, a: np.ndarray,
                    j: np.ndarray) -> np.ndarray:
    """Return the peak velocity in (0, top] whose profile over d lasts ``duration`` (bisection)."""
    low, high = np.zeros_like(top), top.copy()
    for _ in range(_BISECTION):
        mid = 0.5 * (low + high)
        with np.errstate(divide='ignore', invalid='ignore'):
            longer = d / mid + _ramp(mid, a, j) > duration
        low, high = np.where(longer, mid, low), np.where(longer, high, mid)
    return high


@dataclass(frozen=True)
class JointProfiles:
    """The seven phases of each joint's profile (see the module), from rest at t = 0."""

    sign: np.ndarray           # (n,) +1 or -1: the direction of each joint's turn
    durations_ns: np.ndarray   # (n, 7) int64, whole nanoseconds
    jerk: np.ndarray           # (n, 7) rad/s^3 in each phase
    acceleration: np.ndarray   # (n, 7) rad/s^2 at each phase's start
    velocity: np.ndarray       # (n, 7) rad/s at each phase's start
    position: np.ndarray       # (n, 8) rad turned at each phase's start, then at the end

    @property
    def ends_ns(self) -> np.ndarray:
        """Return each joint's arrival time (n,), ns."""
        return self.durations_ns.sum(axis=1)

    @property
    def boundaries_ns(self) -> np.ndarray:
        """Return every joint's phase boundaries after 0, sorted and distinct, ns."""
        return np.unique(np.cumsum(self.durations_ns, axis=1)[self.durations_ns > 0])

    def sample(self, t_ns: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """
        Return the turn, velocity, acceleration and jerk of every joint at times t_ns (T,).

        Each (T, n), signed. At a boundary, the phase that starts there; after its arrival a
        joint is at rest at its full turn.
        """
        t = np.asarray(t_ns, dtype=np.int64)[:, None, None]
        starts = np.cumsum(self.durations_ns, axis=1) - self.durations_ns        # (n, 7)
        opens = np.where(self.durations_ns > 0, starts, np.iinfo(np.int64).max)
        phase = np.max(np.where(t >= opens[None], np.arange(7), 0), axis=2)       # (T, n)
        rows = np.arange(self.durations_ns.shape[0])[None, :]
        tau = (t[:, :, 0] - starts[rows, phase]) / _NS
        jerk, acc = self.jerk[rows, phase], self.acceleration[rows, phase]
        vel, pos = self.velocity[rows, phase], self.position[rows, phase]
        turn, speed, accel = advance(tau, pos, vel, acc, jerk)
        done = t[:, :, 0] >= self.ends_ns[None, :]
        turn = np.where(done, self.position[:, -1][None, :], turn)
        moving = np.where(done, 0.0, 1.0)
        return (self.sign * turn, self.sign * speed * moving, self.sign * accel * moving,
                self.sign * jerk * moving)


def _rise_and_cruise(d: np.ndarray, v: np.ndarray, a: np.ndarray, j: np.ndarray,
                     duration: float | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return each joint's jerk, constant-acceleration and cruise times (s), before rounding."""
    top = np.minimum(v, _peak_without_cruise(d, a, j))
    vp = top
    if duration is not None:
        fastest = d / np.where(top > 0.0, top, 1.0) + _ramp(top, a, j)
        target = np.maximum(duration - _ROUNDING_NS / _NS, fastest)
        vp = _stretched_peak(d, target, top, a, j)
    with np.errstate(divide='ignore', invalid='ignore'):
        ap = np.where(vp * j >= a * a, a, np.sqrt(vp * j))
        tj = np.where(np.isfinite(j), ap / j, 0.0)
        rise = np.maximum(vp / ap - tj, 0.0)
        cruise = np.maximum(d / vp - _ramp(vp, a, j), 0.0)
    moving = d > 0.0
    return tuple(np.where(moving, x, 0.0) for x in (tj, rise, cruise))


def _whole_phases(tj: np.ndarray, rise: np.ndarray, cruise: np.ndarray | None,
                  end_ns: np.ndarray | None, moving: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Return the jerk, constant-acceleration and cruise phases in whole nanoseconds.

    None is shorter than ``SHORTEST_NS`` but zero. Each is rounded up; a shorter
    constant-acceleration phase goes into the jerk phases and a shorter cruise into the rise
    (both make the ramps longer and lower the peaks). With ``end_ns``, the cruise fills the
    profile to that end (at least ``SLACK_NS`` later than the fastest, so that cruise is long
    enough).
    """
    jerk_ns, rise_ns = _whole_ns(tj), _whole_ns(rise)
    # a moving joint ramps for at least 1 ns: its jerk phases (jerk-limited), else its rise
    jerk_ns = np.where(moving & (tj > 0.0), np.maximum(jerk_ns, 1.0), jerk_ns)
    rise_ns = np.where(moving & (tj == 0.0), np.maximum(rise_ns, 1.0), rise_ns)
    short = (rise_ns < SHORTEST_NS) & (jerk_ns > 0.0)
    jerk_ns, rise_ns = np.where(short, jerk_ns + rise_ns, jerk_ns), np.where(short, 0.0, rise_ns)
    ramp_ns = 2.0 * jerk_ns + rise_ns
    if end_ns is not None:
        return jerk_ns, rise_ns, np.where(ramp_ns > 0.0, end_ns - 2.0 * ramp_ns, 0.0)
    cruise_ns = _whole_ns(cruise)
    short = (cruise_ns > 0.0) & (cruise_ns < SHORTEST_NS)
    rising = rise_ns > 0.0
    rise_ns = np.where(short & rising, rise_ns + cruise_ns, rise_ns)
    jerk_ns = np.where(short & ~rising, jerk_ns + np.ceil(cruise_ns / 2.0), jerk_ns)
    return jerk_ns, rise_ns, np.where(short, 0.0, cruise_ns)


def joint_profiles(turn: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray,
                   jerk: np.ndarray, synchronized: bool = False) -> JointProfiles:
    """
    Return each joint's profile for a signed ``turn`` (n,) rad within its limits (n,).

    Each joint's fastest profile; with ``synchronized`` every joint's profile stretched to a
    common end (without, only those that would arrive less than ``SNAP_NS`` before the last
    one). Every phase a whole number of nanoseconds (see the module).
    """
    turn = np.asarray(turn, dtype=float)
    d = np.where(np.abs(turn) > SMALLEST_TURN, np.abs(turn), 0.0)
    v, a, j = (np.asarray(x, dtype=float) for x in (velocity, acceleration, jerk))
    jerk_ns, rise_ns, cruise_ns = _whole_phases(*_rise_and_cruise(d, v, a, j, None), None,
                                                d > 0.0)
    end_ns = 2.0 * (2.0 * jerk_ns + rise_ns) + cruise_ns
    last = float(end_ns.max(initial=0.0))
    group = (d > 0.0) & (synchronized | (end_ns > last - SNAP_NS))
    fixed = np.arange(d.size) == np.argmax(end_ns)         # the slowest joint's fastest
    common = last
    if group.sum() > 1:           # a common end, later than any joint's fastest
        common = last + SLACK_NS
        tj, rise, _ = _rise_and_cruise(d, v, a, j, common / _NS)
        together = _whole_phases(tj, rise, None, np.full(d.shape, common), d > 0.0)
        jerk_ns, rise_ns, cruise_ns = (np.where(group, x, y) for x, y in
                                       zip(together, (jerk_ns, rise_ns, cruise_ns)))
    symmetric = np.stack((jerk_ns, rise_ns, jerk_ns, cruise_ns, jerk_ns, rise_ns, jerk_ns),
                         axis=1).astype(np.int64)
    limits = (d, v, a, j)

    def fits(i: int, phases: np.ndarray) -> bool:
        return bool(_within(phases[None], *(x[i:i + 1] for x in limits))[0])

    dodged = _dodge(symmetric, fixed | (d == 0.0), group, int(common), fits)
    ok = _within(dodged, *limits)
    durations = np.where(ok[:, None], dodged, symmetric)
    jerks, accel, vel, pos = _amplitudes(durations, d)
    return JointProfiles(np.where(turn < 0.0, -1.0, 1.0), durations, jerks, accel, vel, pos)


def _later(b: int, taken: np.ndarray) -> int:
    """Return the first boundary from b on that is on, or ``GAP_NS`` from, every one taken."""
    while True:
        near = taken[np.abs(taken - b) < GAP_NS]
        if near.size == 0 or b in near:
            return b
        ahead = near[near > b]
        if ahead.size:
            return int(ahead.min())
        b = int(near.max()) + GAP_NS


def _earlier(b: int, taken: np.ndarray) -> int:
    """Return the last boundary up to b that is on, or ``GAP_NS`` from, every one taken."""
    while True:
        near = taken[np.abs(taken - b) < GAP_NS]
        if near.size == 0 or b in near:
            return b
        behind = near[near < b]
        if behind.size:
            return int(behind.max())
        b = int(near.min()) - GAP_NS


def _dodge(durations: np.ndarray, fixed: np.ndarray, to_end: np.ndarray, common: int,
           fits: Callable[[int, np.ndarray], bool]) -> np.ndarray:
    """
    Return the phases (ns) lengthened so that no two boundaries are closer than ``GAP_NS``.

    Two boundaries of different joints closer than that (or a phase shorter) would make a
    segment of the message so short that the positions' rounding (a double's last bits)
    gives its polynomial a large acceleration and jerk. The ``fixed`` joints keep their
    phases; each other joint in turn lengthens each phase until its end boundary is on a
    boundary taken before or ``GAP_NS`` from all of them. A joint ``to_end`` keeps its end at
    ``common``: its rise is placed from the start, its fall back from the end, and its cruise
    fills the rest; any other must still arrive ``GAP_NS`` before ``common`` (or at it). A
    joint for which that cannot be done keeps its phases. First, though, a joint whose every
    boundary was within ``GAP_NS`` of the same boundary of a joint placed before (joints that
    tie, as the planner's answers often do) takes that joint's phases as placed if they keep it
    within its limits (``fits(i, phases)``): the boundaries are then one.
    """
    out = durations.copy()
    taken = np.concatenate(([0], np.cumsum(out[fixed], axis=1).ravel()))
    placed = [p for p in np.flatnonzero(fixed) if out[p].any()]     # a still joint is no twin
    for i in np.flatnonzero(~fixed):
        unplaced = np.cumsum(durations[i])
        twins = [p for p in placed
                 if np.all(np.abs(np.cumsum(durations[p]) - unplaced) < GAP_NS)
                 and fits(i, out[p])]
        placed.append(i)
        if twins:
            out[i] = out[twins[0]]
            continue
        trial, own = out[i].copy(), [0]
        t = 0
        for k in range(3) if to_end[i] else range(7):
            if trial[k]:
                b = _later(t + int(trial[k]), np.union1d(taken, own))
                trial[k], t = b - t, b
                own.append(b)
        if to_end[i]:
            t = common
            for k in (6, 5, 4):
                if trial[k]:
                    b = _earlier(t - int(trial[k]), np.union1d(taken, own))
                    trial[k], t = t - b, b
                    own.append(b)
            trial[3] = t - trial[:3].sum()
            if trial[3] < 0 or 0 < trial[3] < GAP_NS:
                continue
        elif t != common and t > common - GAP_NS:      # it would arrive too late
            continue
        out[i] = trial
        taken = np.union1d(taken, np.cumsum(trial))
    return out


def _amplitudes(durations: np.ndarray, d: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Return each phase's jerk, and the acceleration, velocity and turn at its start (n, 7).

    The acceleration rises to a_p over the first three phases and falls to -a_f over the last
    three (a_f such that the velocity ends at 0), the peak a_p such that the turn is d;
    ``position`` (n, 8) ends with d itself.
    """
    s = durations / _NS
    rise = s[:, 0] / 2.0 + s[:, 1] + s[:, 2] / 2.0
    fall = s[:, 4] / 2.0 + s[:, 5] + s[:, 6] / 2.0
    with np.errstate(divide='ignore', invalid='ignore'):
        ratio = np.where(fall > 0.0, rise / fall, 0.0)
        inverse = np.where(s > 0.0, 1.0 / s, 0.0)
    ones, none = np.ones_like(ratio), np.zeros_like(ratio)
    jerks = np.stack((ones, none, -ones, none, -ratio, none, ratio), axis=1) * inverse
    accel = np.stack((none, ones, ones, none, none, -ratio, -ratio), axis=1)
    vel, pos = np.zeros_like(s), np.zeros((d.size, 8))
    for k in range(7):                            # the state at each phase's start, then the end
        pos[:, k + 1], at_end, _ = advance(s[:, k], pos[:, k], vel[:, k], accel[:, k],
                                           jerks[:, k])
        if k < 6:
            vel[:, k + 1] = at_end
    with np.errstate(divide='ignore', invalid='ignore'):
        peak = np.where(d > 0.0, d / pos[:, -1], 0.0)[:, None]
    pos = pos * peak
    pos[:, -1] = d                                # the end, exactly
    return jerks * peak, accel * peak, vel * peak, pos


def _within(durations: np.ndarray, d: np.ndarray, v: np.ndarray, a: np.ndarray,
            j: np.ndarray) -> np.ndarray:
    """Return whether each joint's profile of these phases keeps within its limits."""
    jerks, accel, vel, _ = _amplitudes(durations, d)
    margin = 1.0 + 1e-12
    return ((np.max(vel, axis=1) <= v * margin)
            & (np.max(np.abs(accel), axis=1) <= a * margin)
            & (np.max(np.abs(jerks), axis=1) <= j * margin))
