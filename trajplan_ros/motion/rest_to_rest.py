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
at least as long as unrounded, so the limits still hold (a stretched profile is first solved
for 8 ns less than its end, the most the rounding can add). With the rules of
``joint_profiles`` (a common end ``SLACK_NS`` after the slowest joint's fastest, phases under
``SHORTEST_NS`` folded into others) that rounding adds at most about 0.8 µs.

Boundaries apart: the controller's polynomial over a segment is fitted to positions rounded to
doubles, so over a short segment it is off by a large acceleration and jerk. No two
boundaries, of one joint or of two, are closer than a gap (``GAP_NS``, or more where the
positions' rounding asks for it: ``trajectory._segment_ns``) unless they are one (``_place``).
Lengthening any phase (d kept) lowers every amplitude, so the joints make room for each other
by lengthening phases: a joint that is not the slowest keeps its arrival time as a bound,
and the slowest lengthens its phases shorter than a gap (its jerk phases at once, by a lower
jerk limit: ``_quickest``), which makes the motion longer than R by at most a few gaps, where
a phase of the slowest joint is that short (none of it otherwise).
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
#: The least time (ns) between two phase boundaries that are not one, unless more is asked
#: (``joint_profiles``' ``gap_ns``): see ``_place``.
GAP_NS = 500_000
#: How many gaps before the common end the earlier ends of ``_first_to_end`` are.
_EARLIER = (2, 4, 8, 16)
#: How many later common ends ``joint_profiles`` tries, a gap apart, beyond first_ns / gap_ns
#: (16 always suffice: see ``_place``).
_TRIES = 64


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
    gap_ns: int = GAP_NS       # no two distinct boundaries closer, ns
    first_ns: int = GAP_NS     # no boundary earlier after 0, ns

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
        amplitudes = self.jerk, self.acceleration, self.velocity, self.position
        return self._state(t_ns, amplitudes, _NS)

    def turn(self, t_ns: np.ndarray) -> np.ndarray:
        """
        Return every joint's signed turn at times t_ns (T,), (T, n), in ``np.longdouble``.

        As ``sample``'s, with the amplitudes and the phases' states computed again in that
        type: where it is wider than a double (x86-64's 64 bits), to well below a double's
        last bit.
        """
        amplitudes = _amplitudes(self.durations_ns, self.position[:, -1], np.longdouble)
        return self._state(t_ns, amplitudes, np.longdouble(_NS))[0]

    def _state(self, t_ns: np.ndarray, amplitudes: tuple[np.ndarray, ...], ns: float
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Return ``sample``'s values from ``amplitudes`` (``_amplitudes``), ``ns`` ns a second."""
        t = np.asarray(t_ns, dtype=np.int64)[:, None, None]
        starts = np.cumsum(self.durations_ns, axis=1) - self.durations_ns        # (n, 7)
        opens = np.where(self.durations_ns > 0, starts, np.iinfo(np.int64).max)
        phase = np.max(np.where(t >= opens[None], np.arange(7), 0), axis=2)       # (T, n)
        rows = np.arange(self.durations_ns.shape[0])[None, :]
        tau = (t[:, :, 0] - starts[rows, phase]) / ns
        jerks, accel, vel, pos = amplitudes
        turn, speed, acc = advance(tau, pos[rows, phase], vel[rows, phase], accel[rows, phase],
                                   jerks[rows, phase])
        done = t[:, :, 0] >= self.ends_ns[None, :]
        turn = np.where(done, pos[:, -1][None, :], turn)
        moving = np.where(done, 0.0, 1.0)
        return (self.sign * turn, self.sign * speed * moving, self.sign * acc * moving,
                self.sign * jerks[rows, phase] * moving)


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


def _symmetric(jerk_ns: np.ndarray, rise_ns: np.ndarray, cruise_ns: np.ndarray) -> np.ndarray:
    """Return the seven phases (n, 7) of profiles whose fall mirrors their rise, int64 ns."""
    return np.stack((jerk_ns, rise_ns, jerk_ns, cruise_ns, jerk_ns, rise_ns, jerk_ns),
                    axis=1).astype(np.int64)


def _stretched(d: np.ndarray, v: np.ndarray, a: np.ndarray, j: np.ndarray,
               end_ns: np.ndarray) -> np.ndarray:
    """Return each profile stretched to end at ``end_ns`` (n,), in whole nanoseconds."""
    tj, rise, _ = _rise_and_cruise(d, v, a, j, end_ns / _NS)
    return _symmetric(*_whole_phases(tj, rise, None, end_ns, d > 0.0))


def _quickest(d: np.ndarray, v: np.ndarray, a: np.ndarray, j: np.ndarray,
              ramps: tuple[int, ...]) -> list[np.ndarray]:
    """
    Return each joint's fastest profile, then its fastest with ramps of each of ``ramps`` (ns).

    A jerk phase (trapezoidal: a rise) shorter than the gap between boundaries is lengthened
    when the profile is placed (``_forward``), and so is each of the three (one) like it; a
    lower limit, j = a / ramp (a = v / ramp), makes them that long at once, for less time.
    """
    out = []
    for ramp in dict.fromkeys((0,) + ramps):
        lower_a, lower_j = a, j
        if ramp:
            jerky = np.isfinite(j)
            lower_j = np.where(jerky, np.minimum(j, a * _NS / ramp), j)
            lower_a = np.where(jerky, a, np.minimum(a, v * _NS / ramp))
        out.append(_symmetric(*_whole_phases(*_rise_and_cruise(d, v, lower_a, lower_j, None),
                                             None, d > 0.0)))
    return out


def joint_profiles(turn: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray,
                   jerk: np.ndarray, synchronized: bool = False, gap_ns: int = GAP_NS,
                   first_ns: int = 0) -> JointProfiles:
    """
    Return each joint's profile for a signed ``turn`` (n,) rad within its limits (n,).

    Each joint's fastest profile; with ``synchronized`` every joint's profile stretched to a
    common end (without, only those that would arrive less than ``SNAP_NS`` before the last
    one). Every phase a whole number of nanoseconds, and no two boundaries, of one joint or
    of two, less than ``gap_ns`` apart unless they are one, nor any before ``first_ns`` (see
    the module and ``_place``).
    """
    turn = np.asarray(turn, dtype=float)
    d = np.where(np.abs(turn) > SMALLEST_TURN, np.abs(turn), 0.0)
    v, a, j = (np.asarray(x, dtype=float) for x in (velocity, acceleration, jerk))
    gap = max(int(gap_ns), 1)
    first = max(int(first_ns), gap)
    quick = _quickest(d, v, a, j, (gap, first))
    ends = quick[0].sum(axis=1)
    last = int(ends.max(initial=0))
    group = (d > 0.0) & (synchronized | (ends > last - SNAP_NS))
    slowest = int(np.argmax(ends))
    # the slowest joint's phases lengthened to the gap, the quickest way: the end of the others
    own = min((_forward(q[slowest], np.zeros(1, dtype=np.int64), gap, first) for q in quick),
              key=np.sum)
    end = int(own.sum()) + (int(SLACK_NS) if group.sum() > 1 else 0)
    limits = (d, v, a, j)
    for _ in range(_TRIES + first // gap):
        durations = _place(quick, group, slowest, own, end, limits, gap, first)
        if durations is not None:
            break
        end += gap                # a common end a gap later leaves every joint more room
    else:                         # pragma: no cover - see _place: it never comes to this
        raise RuntimeError('no profile keeps its phase boundaries apart')
    jerks, accel, vel, pos = _amplitudes(durations, d)
    return JointProfiles(np.where(turn < 0.0, -1.0, 1.0), durations, jerks, accel, vel, pos,
                         gap, first)


def _later(b: int, taken: np.ndarray, gap: int) -> int:
    """Return the first boundary from b on that is on, or ``gap`` from, every one taken."""
    while True:
        near = taken[np.abs(taken - b) < gap]
        if near.size == 0 or b in near:
            return b
        ahead = near[near > b]
        if ahead.size:
            return int(ahead.min())
        b = int(near.max()) + gap


def _earlier(b: int, taken: np.ndarray, gap: int) -> int:
    """Return the last boundary up to b that is on, or ``gap`` from, every one taken."""
    while True:
        near = taken[np.abs(taken - b) < gap]
        if near.size == 0 or b in near:
            return b
        behind = near[near < b]
        if behind.size:
            return int(behind.max())
        b = int(near.min()) - gap


def _forward(phases: np.ndarray, taken: np.ndarray, gap: int, first: int) -> np.ndarray:
    """
    Return the phases, each lengthened until its end is on a boundary or ``gap`` from all.

    ``taken``: the other joints' boundaries; the joint's own count too, so that none of its
    phases is shorter than ``gap``. Each phase grows by less than 2 ``gap`` (the first ends
    ``first`` or later).
    """
    trial, own, t = phases.copy(), [0], 0
    for k in range(7):
        if trial[k]:
            b = _later(max(t + int(trial[k]), first), np.union1d(taken, own), gap)
            trial[k], t = b - t, b
            own.append(b)
    return trial


def _to_end(phases: np.ndarray, taken: np.ndarray, end: int, gap: int, first: int
            ) -> np.ndarray | None:
    """
    Return the phases placed to end at ``end``, or None if they do not fit in it.

    As ``_forward``, the rise from the start and the fall back from ``end``; the cruise fills
    the rest and must be none or at least ``gap`` long.
    """
    trial, own, t = phases.copy(), [0, end], 0
    for k in (0, 1, 2):
        if trial[k]:
            b = _later(max(t + int(trial[k]), first), np.union1d(taken, own), gap)
            trial[k], t = b - t, b
            own.append(b)
    rise, t = t, end
    for k in (6, 5, 4):
        if trial[k]:
            b = _earlier(t - int(trial[k]), np.union1d(taken, own), gap)
            trial[k], t = t - b, b
            own.append(b)
    trial[3] = t - rise
    return None if trial[3] < 0 or 0 < trial[3] < gap else trial


def _place(quick: list[np.ndarray], group: np.ndarray, slowest: int, own: np.ndarray,
           end: int, limits: tuple[np.ndarray, ...], gap: int, first: int
           ) -> np.ndarray | None:
    """
    Return every joint's phases (n, 7), no two boundaries closer than ``gap`` but equal ones.

    Over a shorter segment of the message the rounding of the positions (a double's last bits)
    would give the controller's polynomials a large acceleration and jerk. The joints are
    placed in turn, the slowest first, each keeping to the boundaries placed before: a joint
    whose every boundary is within ``gap`` of the same one of a joint placed before (joints
    that tie, as the planner's answers often do) takes that joint's phases as placed if they
    keep it within its limits; any other lengthens its phases (``_forward``, which only lowers
    its amplitudes) and must arrive ``gap`` before ``end``, or at it. A joint of the ``group``
    (and one that would arrive later) ends at ``end`` (``_to_end``): its profile stretched to
    ``end``, else to earlier ends (which leave a longer cruise for the ramps to grow into),
    else its ``quick`` profiles (``_quickest``), the first that fits and keeps its limits.
    None if a joint fits none. Each boundary moves by less than 2 gaps (the first by less than
    ``first`` and 2 gaps), so an end ``first`` and 13 gaps after a joint's fastest leaves its
    fastest room for a cruise of at least a gap, all its phases no shorter: it fits.
    """
    d, fastest = limits[0], quick[0]
    bases = fastest
    stretch = group & ((np.arange(d.size) != slowest) | (int(own.sum()) != end))
    if stretch.any():
        bases = np.where(stretch[:, None], _stretched(*limits, np.full(d.shape, float(end))),
                         fastest)
    out = np.zeros_like(fastest)
    taken = np.zeros(1, dtype=np.int64)
    placed: list[int] = []

    def fits(i: int, phases: np.ndarray) -> bool:
        return bool(_within(phases[None], *(x[i:i + 1] for x in limits))[0])

    for i in [slowest] + [k for k in range(d.size) if k != slowest]:
        if d[i] == 0.0:
            continue
        if i == slowest and int(own.sum()) == end:
            phases = own
        else:
            unplaced = np.cumsum(bases[i])
            twins = [p for p in placed
                     if np.all(np.abs(np.cumsum(bases[p]) - unplaced) < gap)
                     and (not group[i] or int(out[p].sum()) == end) and fits(i, out[p])]
            phases = out[twins[0]] if twins else None
            if phases is None and not group[i]:
                phases = _forward(bases[i], taken, gap, first)
                arrive = int(phases.sum())
                if (arrive != end and arrive > end - gap) or not fits(i, phases):
                    phases = None
            if phases is None:
                phases = _first_to_end(i, [bases[i]] + [q[i] for q in quick], taken,
                                       (end, gap, first), fits, limits)
            if phases is None:
                return None
        out[i] = phases
        placed.append(i)
        taken = np.union1d(taken, np.cumsum(phases))
    return out


def _first_to_end(i: int, profiles: list[np.ndarray], taken: np.ndarray,
                  times: tuple[int, int, int], fits: Callable[[int, np.ndarray], bool],
                  limits: tuple[np.ndarray, ...]) -> np.ndarray | None:
    """
    Return joint i's first profile that ``_to_end`` places within its limits, or None.

    ``profiles``: joint i's stretched to the end, then its quick ones; ``times``: the end,
    the gap and the first boundary's least time (ns).
    """
    base, fastest = profiles[0], profiles[1]
    end, gap, first = times
    trial = _to_end(base, taken, end, gap, first)
    if trial is not None and fits(i, trial):
        return trial
    quickest = int(fastest.sum())
    earlier = [end - k * gap for k in _EARLIER if end - k * gap > quickest]
    candidates = profiles[1:]
    if earlier:
        one = [x[i:i + 1].repeat(len(earlier)) for x in limits]
        candidates = list(_stretched(*one, np.array(earlier, dtype=float))) + candidates
    for phases in candidates:
        trial = _to_end(phases, taken, end, gap, first)
        if trial is not None and fits(i, trial):
            return trial
    return None


def _amplitudes(durations: np.ndarray, d: np.ndarray, dtype: type = float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Return each phase's jerk, and the acceleration, velocity and turn at its start (n, 7).

    The acceleration rises to a_p over the first three phases and falls to -a_f over the last
    three (a_f such that the velocity ends at 0), the peak a_p such that the turn is d;
    ``position`` (n, 8) ends with d itself. Computed in ``dtype``.
    """
    s = durations.astype(dtype) / dtype(_NS)
    rise = s[:, 0] / 2.0 + s[:, 1] + s[:, 2] / 2.0
    fall = s[:, 4] / 2.0 + s[:, 5] + s[:, 6] / 2.0
    with np.errstate(divide='ignore', invalid='ignore'):
        ratio = np.where(fall > 0.0, rise / fall, 0.0)
        inverse = np.where(s > 0.0, 1.0 / s, 0.0)
    ones, none = np.ones_like(ratio), np.zeros_like(ratio)
    jerks = np.stack((ones, none, -ones, none, -ratio, none, ratio), axis=1) * inverse
    accel = np.stack((none, ones, ones, none, none, -ratio, -ratio), axis=1)
    vel, pos = np.zeros_like(s), np.zeros((d.size, 8), dtype=dtype)
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
