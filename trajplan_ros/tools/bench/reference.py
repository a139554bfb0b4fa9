# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Exact minimum motion time for the paper's arm family, for tests and benchmarks only.

Reaching a point with the yaw + three-parallel-pitch joints of Lv et al.'s arm leaves one free
parameter, phi = theta2 + theta3 + theta4 (DH). For each phi there are at most four exact
solutions: two base branches (q1 = atan2(y, x) with r = +rho, or q1 +- pi with r = -rho) and two
elbow branches of the planar a2/a3 pair (doc/paper.md, "The exact reference"). A dense sweep over
phi followed by zooming in on the best samples gives the true minimum of R (eq. 10) to about
1e-10 s. R may be any profile's (``motion_profile``): its duration max_i t_i(|q_i - start_i|)
is what is swept. The planner never calls this: it only exists to check optimisers
independently.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trajplan_ros.kinematics import ArmModel
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.motion.time_law import motion_times, TimeLaw

__all__ = ['ExactOptimum', 'exact_minimum', 'radial_angle']


@dataclass(frozen=True)
class ExactOptimum:
    """The true minimum motion time and one configuration that attains it (NaN when none)."""

    motion_time_s: float
    joint_goal: np.ndarray


def radial_angle(goal: np.ndarray) -> float:
    """Return eps of eq. (13), the angle between the base z axis and the goal p, in [0, pi]."""
    g = np.asarray(goal, dtype=float)
    return float(np.arccos(np.clip(g[2] / np.linalg.norm(g), -1.0, 1.0)))


def _check_family(arm: ArmModel) -> None:
    half = np.pi / 2
    dh = arm.dh
    ok = dh is not None and arm.planned == 4 and arm.n_joints == 5
    if ok:
        a, alpha, d = dh
        ok = (np.isclose(alpha[0], -half) and np.allclose(alpha[1:3], 0.0)
              and np.isclose(alpha[3], half) and np.allclose(d[:4], 0.0) and a[4] == 0.0
              and np.all(arm.velocity[:4] == np.inf))
    if not ok:
        raise ValueError("exact_minimum only knows arms shaped like the paper's (Table 3)")


def _solutions(arm: ArmModel, goal: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Return all exact solutions q (len(phi), 4 branches, 4) for each phi; NaN where none."""
    a, _, d = arm.dh
    a1, a2, a3, a4 = a[:4]
    d5 = d[4]
    x, y, z = goal
    rho = np.hypot(x, y)
    out = np.full((phi.size, 4, 4), np.nan)
    base = np.arctan2(y, x)
    cphi, sphi = np.cos(phi), np.sin(phi)
    v = d5 * cphi - a4 * sphi - z
    for b, (theta1, r) in enumerate(((base, rho), (base + np.pi, -rho))):
        u = r - a1 - a4 * cphi - d5 * sphi
        c3 = (u * u + v * v - a2 * a2 - a3 * a3) / (2 * a2 * a3)
        ok = np.abs(c3) <= 1.0
        for e, elbow in enumerate((1.0, -1.0)):
            t3 = elbow * np.arccos(np.clip(c3, -1.0, 1.0))
            t2 = np.arctan2(v, u) - np.arctan2(a3 * np.sin(t3), a2 + a3 * np.cos(t3))
            t4 = phi - t2 - t3
            theta = np.stack((np.full_like(phi, theta1), t2, t3, t4), axis=1)
            q = (theta - arm.offset[:4]) / arm.sign[:4]
            q = np.mod(q + np.pi, 2 * np.pi) - np.pi
            q[~ok] = np.nan
            out[:, 2 * b + e] = q
    return out


def _times(arm: ArmModel, q: np.ndarray, start: np.ndarray, law: TimeLaw) -> np.ndarray:
    inside = np.all((q >= arm.lower[:4]) & (q <= arm.upper[:4]), axis=-1)
    rows = np.ascontiguousarray(np.nan_to_num(q.reshape(-1, 4)))
    t = motion_times(law, rows, np.ascontiguousarray(start[:4])).reshape(q.shape[:-1])
    return np.where(inside, t, np.inf)


def _zoom(arm: ArmModel, goal: np.ndarray, start: np.ndarray, law: TimeLaw,
          sweep: tuple[np.ndarray, np.ndarray, np.ndarray], zoom_levels: int,
          tmin: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """
    Zoom in from ``sweep`` (phi samples, their solutions, their times) on the least time.

    Return the last level's solutions and their times.

    With ``tmin``, zoom in on the least total joint travel among the samples whose time ties
    with ``tmin`` instead.
    """
    phis, q, t = sweep
    step = phis[1] - phis[0]
    for _ in range(zoom_levels):
        if tmin is not None:
            t = np.where(t <= tmin * (1 + 1e-12) + 1e-15, np.abs(q - start[:4]).sum(axis=-1),
                         np.inf)
        t = t.min(axis=1)
        finite = np.isfinite(t)
        if not finite.any():
            break
        best = phis[finite][np.argsort(t[finite])[:16]]
        step /= 50.0
        phis = np.unique((best[:, None] + np.arange(-100, 101)[None, :] * step).ravel())
        q = _solutions(arm, goal, phis)
        t = _times(arm, q, start, law)
    q = q.reshape(-1, 4)
    return q, _times(arm, q, start, law)


def exact_minimum(arm: ArmModel, goal: np.ndarray, start: np.ndarray, *, omega: float = 0.2,
                  mode: str = 'free', zoom_levels: int = 5,
                  profile: MotionProfile | None = None) -> ExactOptimum:
    """
    Return the least R = max_i t_i(|q_i - start_i|) over in-limit q that reach ``goal`` exactly.

    t_i is ``profile``'s time law at servo velocity ``omega`` (default the servo's, d / omega).

    mode "free": sweep phi over [-pi, pi]; mode "radial": the tool axis along the goal ray
    (eq. 12-13, doc/paper.md), so phi = +radial_angle(goal) on the base branch facing the goal
    and -radial_angle(goal) on the one turned away. Among configurations that tie at the least
    R (relative 1e-12), the one with the least total joint travel sum |q_i - start_i| is
    returned, as the planner does: in free mode, where a whole arc of the solutions ties (the
    slowest joint does not move along it), by a second zoom over the tied samples.
    """
    _check_family(arm)
    whole = (profile or MotionProfile()).time_law(arm, omega)
    law = TimeLaw(whole.kind, *(np.ascontiguousarray(x[:4]) for x in whole[1:]))
    goal = np.asarray(goal, dtype=float)
    start = np.asarray(start, dtype=float)
    if mode == 'radial':
        both = _solutions(arm, goal, np.array([radial_angle(goal), -radial_angle(goal)]))
        q = np.concatenate((both[0, :2], both[1, 2:]))       # facing: +eps; turned: -eps
        t = _times(arm, q, start, law)
    elif mode == 'free':
        phis = np.linspace(-np.pi, np.pi, 20001)
        solved = _solutions(arm, goal, phis)
        sweep = (phis, solved, _times(arm, solved, start, law))
        q, t = _zoom(arm, goal, start, law, sweep, zoom_levels)
        tmin = float(t.min())
        if np.count_nonzero(sweep[2] <= tmin * (1 + 1e-9)) > 1:
            q2, t2 = _zoom(arm, goal, start, law, sweep, zoom_levels, tmin)   # a tied arc
            q, t = np.concatenate((q, q2)), np.concatenate((t, t2))
    else:
        raise ValueError(f"mode must be 'free' or 'radial', got {mode!r}")
    if not np.isfinite(t).any():
        return ExactOptimum(np.inf, np.full(4, np.nan))
    tied = np.flatnonzero(t <= t.min() * (1 + 1e-12) + 1e-15)
    travel = np.abs(q[tied] - start[:4]).sum(axis=1)
    return ExactOptimum(float(t[tied].min()), q[tied[np.argmin(travel)]].copy())
