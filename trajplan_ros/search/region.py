# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Least motion time within a goal's tolerances: the target moved inside its region (ours).

A goal's tolerances make it a region: the tool point within ``tolerance`` of the goal (a
ball), the tool axis within ``axis_tolerance`` of its target (a cone), a pose's orientation
within ``orientation_tolerance`` of the goal's (a ball of rotations). The search plans
exactly to the region's centre; ``within_tolerances`` then moves the target inside the
region to where the exact plan is fastest.

Let T*(y) be the least motion time (R, eq. 10) of the exact plan to target y: the point g'
and the axis or orientation turned by a rotation vector rho from the goal's. At an exact plan
x the Lagrange multipliers lambda of its constraints c(x; y) = 0 give its gradient
(``target_gradient``): dT*/dg' = lambda_p and dT*/drho = -lambda^T dc/drho. They solve the
KKT conditions of min R subject to c = 0 (``multipliers``): J^T lambda is a combination,
with weights mu_i >= 0 summing to one, of the gradients of the joints' times t_i that tie
with R, plus any multiple of a joint's unit vector where it lies on a limit.

T* is nearly linear across a small region, so its least value there lies on the boundary
against the gradient, on each ball alone (the region is their product): g' = g - r_p
lambda_p / |lambda_p| and rho = -r_a grad / |grad|. Each step re-plans exactly to the new
target from the last answer (``polish.polish``), up to ``STEPS`` times, until the target
moves less than ``SETTLED`` of the radius. A step that ends slower than the best so far has
crossed a change of the joints that tie with R (a kink of T*): its target goes halfway back,
again while it is slower (``BACKTRACKS``), and the next step is against the least
combination of the gradients on both sides (``_least_of``, a bundle step). The walk starts at
the target the plan reaches (``_reached_target``), and the fastest answer inside the region
wins; the plan stands when none is faster. Radii of at most
``EXACT`` are the goal itself (they could gain some 1e-6 of R), so the default tolerances
leave plans as they are.

An objective that holds one component of the axis (``Objective.in_plane``, a pan-and-pitch
arm) leaves the other where the joints put it, so its axis can end further from the target
than the target turned: secant steps then shrink the turn until the axis is inside. (Walking
such a plan holding both components as well never found a faster point: 0 of 90 SO-101
picks from above with cones of 0.001 to 0.05 rad.)

Being local, the walk finds the fastest point of the region near the plan to its centre: a
faster one that needs another branch of the solutions (an SO-101 pick whose fastest axis in a
0.01 rad cone turns the wrist roll the other way; a Panda pose whose fastest orientation
within 0.05 rad is 15 % faster with joints 3 and 5 on their other side) is not found.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from trajplan_ros.kinematics.rotations import (quaternion_of_turn, quaternions, rotation_matrix,
                                               turn_of_quaternion)
from trajplan_ros.search.goal import Mode
from trajplan_ros.search.objective import Objective
from trajplan_ros.search.polish import polish

__all__ = ['Region', 'multipliers', 'target_gradient', 'within_tolerances']

#: Steps to a moved target at most.
STEPS = 8
#: Times a step that ends slower goes halfway back, at most.
BACKTRACKS = 5
#: Polish steps of a re-plan at most (from the last answer most take a few; a large turn near
#: a wrist singularity takes more).
POLISH_STEPS = 30
#: Re-plans that bring an axis held in one component back into the region, at most.
FIT = 4
#: The target has settled when a step moves it less than this fraction of the radius.
SETTLED = 1e-4
#: A joint ties with R when its time is within this fraction of R: the polish leaves the
#: tying joints' times apart by up to some 1e-5 of R (an SO-101 plan: 4e-6), and a tie missed
#: leaves no multipliers, so no step at all.
TIE = 1e-4
#: A joint lies on a limit within this many radians.
ON_LIMIT = 1e-9
#: A radius of at most this (m or rad) is the goal itself: it could gain some 1e-6 of R.
EXACT = 1e-6
#: No step is taken when the first-order gain is below this fraction of R.
LEAST_GAIN = 1e-4
#: Nor when the step's first-order gain is below this fraction of R.
LEAST_STEP_GAIN = 1e-6
#: The targets aim this fraction inside each radius, so that rounding (and the secant steps
#: of an axis held in one component) keep the answer in.
INSIDE = 1e-5
#: An answer counts as on its moved target with residuals below this (m, rad).
ON_TARGET = 1e-8


class Region(NamedTuple):
    """A goal's region: the position's radius (m) and the axis's or orientation's (rad)."""

    position: float
    angle: float


class Target(NamedTuple):
    """A point of the region: the goal moved by ``shift`` (m), turned by ``turn`` (rad)."""

    shift: np.ndarray
    turn: np.ndarray


def _joint_times(obj: Objective, x: np.ndarray, *scales: float) -> np.ndarray:
    """Return each planned joint's time t_i(scale |x_i - start_i|) alone, per scale (s)."""
    s = obj.planned_start
    alone = np.where(np.eye(s.size, dtype=bool)[None],
                     s + np.reshape(scales, (-1, 1, 1)) * (x - s), s)
    return obj.motion_time(alone.reshape(-1, s.size)).reshape(len(scales), s.size)


def constraint_jacobian(obj: Objective, x: np.ndarray) -> np.ndarray:
    """Return dc/dx (constraints, planned) at the planned joints x (``Objective.residuals``)."""
    d = obj.tool_jacobian(x[None])
    return obj.linear_residuals(*(j[0].T for j in d.jacobians())).T


def multipliers(obj: Objective, x: np.ndarray) -> np.ndarray | None:
    """
    Return lambda: dT*/dc of the exact plan x to ``obj``'s target (module docstring).

    The joints that neither tie with R nor lie on a limit give J^T lambda = 0; the tying ones
    fix its scale: sum_i sign(d_i) (J^T lambda)_i / t_i'(|d_i|) = 1 (the weights sum to one).
    None when R = 0 or those equations have no solution (a KKT point moves no target).
    """
    d, h = x - obj.planned_start, 1e-6
    times, ahead, behind = _joint_times(obj, x, 1.0, 1.0 + h, 1.0 - h)
    longest = times.max()
    if not longest > 0.0:
        return None
    ties = times >= longest * (1.0 - TIE)
    slope = (ahead - behind) / (2.0 * h * np.maximum(np.abs(d), 1e-300))
    limit = (x - obj.lower <= ON_LIMIT) | (obj.upper - x <= ON_LIMIT)
    free = ~(ties | limit)
    ties &= ~limit                  # a tying joint on a limit has a multiplier of each kind
    still = ties & ~(slope > 0.0)   # a tying joint at its start: moving it costs nothing yet
    free |= still
    ties &= ~still
    if not ties.any():
        return None
    jt = constraint_jacobian(obj, x).T                      # (planned, constraints)
    rows = np.vstack((jt[free], (np.sign(d[ties]) / slope[ties]) @ jt[ties]))
    if not np.all(np.isfinite(rows)):
        return None
    rhs = np.zeros(rows.shape[0])
    rhs[-1] = 1.0
    lam = np.linalg.lstsq(rows, rhs, rcond=None)[0]
    misfit = np.linalg.norm(rows[:-1] @ lam) / (np.linalg.norm(rows) * np.linalg.norm(lam))
    return lam if np.all(np.isfinite(lam)) and misfit <= 1e-6 else None


def target_gradient(obj: Objective, x: np.ndarray, lam: np.ndarray) -> Target:
    """
    Return (dT*/dg', dT*/drho) at the exact plan x, from its multipliers ``lam``.

    A residual c_k = sum_t a_t . b_kt (a_t the tool axis u, or a pose's second axis w; b_kt
    of ``Objective.across_basis``) changes by rho . (b_kt x a_t) when the target turns by rho.
    """
    turn = np.zeros(3)
    if obj.holds_axis:
        axes = obj.tool(x[None])[1:, 0]                           # (V - 1, 3)
        held = obj.across_basis                                   # (h, V - 1, 3)
        dc = np.cross(held, axes[None, : held.shape[1]]).sum(axis=1)   # (h, 3)
        turn = -(lam[3:] @ dc)
    return Target(lam[:3].copy(), turn)


def _moved(obj: Objective, target: Target, frame: np.ndarray) -> Objective:
    """Return the objective of the goal moved to ``target``; ``frame``: the goal's (module)."""
    turned = rotation_matrix(quaternion_of_turn(target.turn)) @ frame
    aim = quaternions(turned[None])[0] if obj.mode is Mode.POSE else turned[:, 0]
    return obj.aimed(obj.goal + target.shift, aim)


def _reached_target(obj: Objective, x: np.ndarray) -> Target:
    """
    Return the target that x reaches exactly: where its tool point is, its axis (or frame).

    The plan of a search reaches the goal to rounding, but one that holds the axis in one
    component (``Objective.in_plane``) leaves the other where the joints put it.
    """
    tool = obj.tool(x[None])[:, 0]
    shift = tool[0] - obj.goal
    if not obj.holds_axis or len(obj.across_basis) == (3 if obj.mode is Mode.POSE else 2):
        return Target(shift, np.zeros(3))          # every component held: on the target
    if obj.mode is not Mode.POSE:                  # the least turn of the target onto u
        axis = np.cross(obj.axis_target, tool[1])
        along, angle = np.linalg.norm(axis), np.arctan2(np.linalg.norm(axis),
                                                        obj.axis_target @ tool[1])
        return Target(shift, axis * (angle / along) if along > 0.0 else np.zeros(3))
    turned = np.stack((tool[1], tool[2], np.cross(tool[1], tool[2])), axis=1) @ obj.ray_basis
    return Target(shift, turn_of_quaternion(quaternions(turned[None])[0]))


def _step(radius: float, gradient: np.ndarray) -> np.ndarray:
    """Return the point of the ball of ``radius`` least along ``gradient``, a little inside."""
    size = np.linalg.norm(gradient)
    if not (radius > 0.0 and size > 0.0):
        return np.zeros(3)
    return -radius * (1.0 - INSIDE) * gradient / size


def _goal_frame(obj: Objective) -> np.ndarray:
    """Return the frame whose first column is the axis target (a pose: its orientation)."""
    if obj.mode is Mode.POSE:
        return rotation_matrix(obj.orientation)
    return obj.ray_basis.T


def within_tolerances(obj: Objective, x: np.ndarray, region: Region) -> np.ndarray:
    """
    Return the fastest joint goal (planned joints) found inside ``region`` from the plan x.

    x is the exact plan to ``obj``'s goal; the answer is x itself when no faster one lies
    inside the region (see the module). Where a step ends slower than the best so far (past a
    change of the joints that tie with R), its target goes halfway back to the best one, up to
    ``BACKTRACKS`` times.
    """
    position = region.position if region.position > EXACT else 0.0
    angle = region.angle if obj.holds_axis and region.angle > EXACT else 0.0
    if position == angle == 0.0:
        return x
    frame = _goal_frame(obj)
    best = _Plan(x, float(obj.motion_time(x[None])[0]), _reached_target(obj, x))
    here, at, previous = _moved(obj, best.target, frame), x, None
    for _ in range(STEPS):
        lam = multipliers(here, at)
        if lam is None:
            break
        gradient = target_gradient(here, at, lam)
        if (position * np.linalg.norm(gradient.shift)
                + angle * np.linalg.norm(gradient.turn)) <= LEAST_GAIN * best.time:
            break
        way = gradient if previous is None else _least_of(previous, gradient, (position, angle))
        target = Target(_step(position, way.shift), _across_axis(obj, _step(angle, way.turn)))
        if -sum(g @ (a - b) for g, a, b in zip(gradient, target, best.target)) <= (
                LEAST_STEP_GAIN * best.time):
            break                                       # settled to first order
        found, previous = _reach_inside(obj, frame, target, at, region), None
        for _ in range(BACKTRACKS):                     # past a kink of T*: back halfway
            if found is None or found.time < best.time:
                break
            target = Target(*(0.5 * (a + b) for a, b in zip(best.target, found.target)))
            found, previous = _reach_inside(obj, frame, target, at, region), gradient
        if found is None or found.time >= best.time:
            break
        moved = max(_size(found.target.shift - best.target.shift, position),
                    _size(found.target.turn - best.target.turn, angle))
        best, here, at = found, found.objective, found.x
        if moved <= SETTLED:
            break
    return best.x


def _least_of(a: Target, b: Target, radii: tuple[float, float]) -> Target:
    """
    Return the least combination of gradients a and b across a kink of T* (a bundle step).

    The point of the segment between them nearest zero, each part scaled by its radius: on a
    ball the step against it lowers both pieces of T* as far as they can go together.
    """
    sa = np.concatenate([r * g for r, g in zip(radii, a)])
    sb = np.concatenate([r * g for r, g in zip(radii, b)])
    gap = sb - sa
    mu = float(np.clip(sb @ gap / (gap @ gap), 0.0, 1.0)) if gap @ gap > 0.0 else 0.0
    return Target(*(mu * p + (1.0 - mu) * q for p, q in zip(a, b)))


class _Plan(NamedTuple):
    """An exact plan x to a target of the region, its motion time, its objective."""

    x: np.ndarray
    time: float
    target: Target
    objective: Objective | None = None


def _reach_inside(obj: Objective, frame: np.ndarray, target: Target, x: np.ndarray,
                  region: Region) -> _Plan | None:
    """
    Return the exact plan to ``target`` from x, turned back into the region where needed.

    The axis of an objective that holds one component of it (``Objective.in_plane``) can
    end further from the axis target than the target turned: the turn then shrinks (secant
    steps on the angle reached, up to ``FIT`` re-plans). None when the polish does not reach
    a target or the plan ends outside the region.
    """
    aim, scale, before = region.angle * (1.0 - INSIDE), 1.0, None
    for _ in range(FIT):
        here = _moved(obj, target._replace(turn=scale * target.turn), frame)
        at = polish(here, x[None], max_steps=POLISH_STEPS)[0]
        if np.linalg.norm(here.residuals(here.tool(at[None]))[0]) > ON_TARGET:
            return None
        tool = obj.tool(at[None])
        if _inside(obj, tool, region):
            return _Plan(at, float(obj.motion_time(at[None])[0]),
                         target._replace(turn=scale * target.turn), here)
        angle = float(obj.angle_errors(tool)[0]) if obj.holds_axis else 0.0
        if not angle > region.angle:
            return None
        # the secant on angle(scale) = aim (the first step: the ratio)
        slope = angle / scale if before is None else (angle - before[1]) / (scale - before[0])
        before, scale = (scale, angle), scale + (aim - angle) / slope
    return None


def _size(v: np.ndarray, radius: float) -> float:
    """Return |v| as a fraction of ``radius`` (0 for a radius of 0)."""
    return float(np.linalg.norm(v) / radius) if radius > 0.0 else 0.0


def _across_axis(obj: Objective, turn: np.ndarray) -> np.ndarray:
    """Return ``turn`` without its part about the axis target (it does not turn the axis)."""
    if obj.mode is Mode.POSE:
        return turn
    axis = obj.axis_target
    across = turn - (turn @ axis) * axis
    size = np.linalg.norm(across)
    return across if size <= 0.0 else across * (np.linalg.norm(turn) / size)


def _inside(obj: Objective, tool: np.ndarray, region: Region) -> bool:
    """Tell whether ``tool`` (V, 1, 3) lies inside ``region`` about ``obj``'s goal."""
    return bool(np.linalg.norm(tool[0, 0] - obj.goal) <= region.position
                and (not obj.holds_axis or obj.angle_errors(tool)[0] <= region.angle))
