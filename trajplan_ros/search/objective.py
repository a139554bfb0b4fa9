# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The efficiency scalar F = R + S of Lv et al. 2019 (eq. 9-14) for one goal and start.

R (eq. 10) is the motion time when every servo turns at the same angular velocity omega:
max_i |q_i - q_start_i| / omega over the planned joints. A joint whose velocity limit is below
omega turns at its limit instead: R = max_i |q_i - q_start_i| / omega_i with
omega_i = min(omega, limit_i) (``speeds``; the paper's arm has no such limit). Under an
acceleration- or jerk-limited profile (``motion_profile``) R is that profile's duration,
max_i t_i(|q_i - q_start_i|) (``time_law``). S is the fuzzy rewards-and-punishment term on the
error (eq. 11, ``fuzzy.RewardPunishment``).

Mode "free" constrains only the tool position. Mode "radial" adds the orientation constraint of
eq. (12)-(13): the tool sweeps from upright by eps = arccos(z . p / |z||p|) towards the goal, so
its axis ends along the goal ray, pointing outward: u_tool = p / |p| (doc/paper.md). On the
paper's arm that is theta2 + theta3 + theta4 = +eps (DH) with the base facing the goal and -eps
with it turned away; written through the tool axis it holds for any chain. The axis error is the
angle between u_tool and p / |p| (``axis_angle``; a tool pointing inward is an error of pi). In
radial mode the error fed to S combines both, err = sqrt(|p - goal|^2 + (L angle)^2), with L
the arm's reach turning radians into metres.

The local polish needs the constraints as smooth residuals: the position residual p - goal and,
in radial mode, the two components of u_tool across the goal ray (``residuals``), which vanish at
u_tool = +-p / |p|; the angle tells the two apart.
"""
from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import NamedTuple

import numpy as np

from trajplan_ros.kinematics import ArmModel, ToolJacobian
from trajplan_ros.kinematics.forward import Chain, tool_rows
from trajplan_ros.kinematics.jit import kernel
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.motion.time_law import motion_times, TimeLaw
from trajplan_ros.search.fuzzy import RewardPunishment, Shaping, shaping_eq9

__all__ = ['Mode', 'Objective', 'Evaluation', 'InvalidRequest', 'Problem', 'errors_eq11',
           'goal_ray_basis']

#: Table 4: angular velocity of every servo, rad/s.
DEFAULT_OMEGA = 0.2
#: Relative slack of the reach check (eq. 14): the tool point of a pose at full stretch,
#: computed in floating point, can lie a few rounding errors beyond the sum of the links.
REACH_ROUNDING = 1e-9


class Mode(str, Enum):
    """Which constraints a plan must meet."""

    FREE = 'free'
    RADIAL = 'radial'


class InvalidRequest(ValueError):
    """A goal or start that is refused before any optimisation (reason in the message)."""


@dataclass(frozen=True)
class Evaluation:
    """Vectorised objective values for N candidate joint goals."""

    efficiency: np.ndarray      # F (eq. 9), s
    motion_time: np.ndarray     # R (eq. 10), s
    error: np.ndarray           # constraint error fed to S (eq. 11), m


def goal_ray_basis(goal: np.ndarray) -> np.ndarray:
    """
    Return the goal ray p / |p| and two unit vectors across it, as the rows of a 3x3 matrix.

    The first vector across is horizontal (z x p normalised; x on the z axis).
    """
    x, y, z = goal / np.sqrt(goal @ goal)
    size = np.hypot(x, y)                                 # of z x ray = (-y, x, 0)
    a, b = (-y / size, x / size) if size > 1e-12 else (1.0, 0.0)
    return np.array([[x, y, z], [a, b, 0.0], [-z * b, z * a, x * b - y * a]])


class Problem(NamedTuple):
    """The kernels' view of an ``Objective``: its arrays, as one argument."""

    chain: Chain            # the planned joints' chain, the held ones at their start
    goal: np.ndarray        # (3,) m
    across: np.ndarray      # (h, 3) the tool axis's components held at zero (``across_basis``)
    ray: np.ndarray         # (3, 3) the goal ray and two vectors across it (``ray_basis``)
    reach: float            # m, L of the error (``errors_eq11``)
    start: np.ndarray       # (m,) the planned joints' start angles
    law: TimeLaw            # each joint's time law: R = max_i t_i(|x_i - start_i|) (eq. 10)
    omega: float            # rad/s
    lower: np.ndarray       # (m,) the search box
    upper: np.ndarray       # (m,)


@kernel
def errors_eq11(p: np.ndarray, u: np.ndarray, goal: np.ndarray, ray: np.ndarray, held: int,
                reach: float) -> np.ndarray:
    """
    Return the error of eq. (11) at tool points p and axes u (N, 3), plus the axis's.

    ``ray``: the goal ray and two unit vectors across it (rows); ``held``: how many of those
    the constraints hold (``Objective.across_basis``). With both, the error adds (L angle)^2,
    the angle between u and the ray; with one, (L asin |u . across|)^2, u's angle from the
    plane that leaves it; L = ``reach``.
    """
    out = np.empty(p.shape[0])
    for k in range(p.shape[0]):
        sq = 0.0
        for a in range(3):
            sq += (p[k, a] - goal[a]) ** 2
        along = u[k, 0] * ray[0, 0] + u[k, 1] * ray[0, 1] + u[k, 2] * ray[0, 2]
        side = u[k, 0] * ray[1, 0] + u[k, 1] * ray[1, 1] + u[k, 2] * ray[1, 2]
        up = u[k, 0] * ray[2, 0] + u[k, 1] * ray[2, 1] + u[k, 2] * ray[2, 2]
        if held == 2:
            sq += (reach * np.arctan2(np.hypot(side, up), along)) ** 2
        elif held == 1:
            sq += (reach * np.arcsin(min(abs(side), 1.0))) ** 2
        out[k] = np.sqrt(sq)
    return out


class Objective:
    """
    F = R + S for reaching ``goal`` from ``start`` with ``arm`` (planned joints only vary).

    ``across`` (radial mode): how many components of the tool axis across the goal ray the
    constraints hold at zero; 2, the axis on the ray, but for ``solution_curve``'s curves.
    ``profile``: the motion's profile and limits (default the paper's servo law); a profile
    that needs a limit no source gives raises ValueError.
    """

    def __init__(self, arm: ArmModel, goal: np.ndarray, start: np.ndarray, *,
                 mode: Mode | str = Mode.FREE, omega: float = DEFAULT_OMEGA,
                 shaping: RewardPunishment | None = None, across: int = 2,
                 profile: MotionProfile | None = None) -> None:
        self.arm = arm
        self.mode = Mode(mode)
        if type(across) is not int or not 0 <= across <= 2:
            raise ValueError(f'across must be 0, 1 or 2, got {across!r}')
        if not (np.isfinite(omega) and omega > 0):
            raise ValueError(f'angular velocity must be finite and positive, got {omega}')
        self.omega = float(omega)
        self.profile = profile if profile is not None else MotionProfile()
        law = self.profile.time_law(arm, self.omega)
        self.shaping = shaping if shaping is not None else RewardPunishment()
        self.goal = self._check_goal(arm, goal)
        if self.radial and not np.any(self.goal):
            raise InvalidRequest('radial mode needs a goal away from the base origin: the goal '
                                 'ray of eq. (12)-(13) has no direction at the origin')
        self.start = self._check_start(arm, start)
        #: The arm as planned: trailing joints that cannot move the tool point (nor, in radial
        #: mode, the tool axis), such as a wrist roll about the tool axis, keep their start
        #: angle, as moving them could only add time.
        self.arm = arm = arm.without_idle_tail(self.radial)
        m = arm.planned
        #: The planned joints' start angles.
        self.planned_start = self.start[:m]
        #: The search box: the joint limits and, for a joint whose range spans more than a turn
        #: (a continuous joint, or limits of +-2 pi), one turn [w, w + 2 pi] with
        #: w = clip(start - pi, lower, upper - 2 pi): q and q +- 2 pi are the same pose, and that
        #: turn holds, of every pose, the angle within the limits nearest the start.
        self.lower, self.upper = self._search_box(arm.lower[:m], arm.upper[:m],
                                                  self.planned_start)
        #: Each planned joint's time law (eq. 10 under the servo profile, t_i = d / omega_i).
        self.law = TimeLaw(law.kind, *(np.ascontiguousarray(v[:m]) for v in law[1:]))
        #: Each planned joint's angular velocity omega_i (rad/s).
        self.speeds = self.law.velocity
        self.err_max = self.shaping.err_max or 2.0 * arm.reach
        #: R of the longest motion the limits allow (s), for the fuzzy rules (Table 1).
        self.longest_time = float(motion_times(self.law, self.upper[None, :], self.lower)[0])
        #: Rows: the goal ray, then two unit vectors across it (radial mode only).
        self.ray_basis = goal_ray_basis(self.goal) if self.radial else np.eye(3)
        #: Rows: the components of the tool axis across the goal ray that the residuals hold at
        #: zero (radial mode: both, unless ``across`` is less, none in free mode). With fewer
        #: than both, the solutions are the larger sets that ``solution_curve`` follows.
        self.across_basis = self.ray_basis[1: 1 + across] if self.radial else np.empty((0, 3))
        self._tail = arm.held_tail(self.start)
        #: The planned joints' chain as the kernels take it, the held ones at their start.
        self.chain = arm.chain(self._tail)
        self._across = across
        self._holding: dict[int, Objective] = {}
        #: The S term's settings as the kernels take them.
        self.shaping_settings = self.shaping.settings(self.err_max)
        #: The objective's arrays as the kernels take them.
        self.problem = Problem(self.chain, self.goal, np.ascontiguousarray(self.across_basis),
                               self.ray_basis, arm.reach, np.ascontiguousarray(self.planned_start),
                               self.law, self.omega, self.lower, self.upper)

    def holding(self, across: int) -> Objective:
        """
        Return the objective of this goal that holds ``across`` components of the tool axis.

        Built once (``solution_curve`` asks for it at every curve search).
        """
        if across == self._across:
            return self
        if across not in self._holding:
            self._holding[across] = Objective(self.arm, self.goal, self.start, mode=self.mode,
                                              omega=self.omega, shaping=self.shaping,
                                              across=across, profile=self.profile)
        return self._holding[across]

    @property
    def null_directions(self) -> int:
        """Return how many directions the solutions leave free: planned joints less constraints."""
        return max(self.arm.planned - 3 - len(self.across_basis), 0)

    @property
    def radial(self) -> bool:
        """Return True in radial mode (the eq. 12-13 orientation constraint applies)."""
        return self.mode is Mode.RADIAL

    @staticmethod
    def _search_box(lower: np.ndarray, upper: np.ndarray,
                    start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return the search box of joints with limits lower, upper from ``start``."""
        turn = upper - lower > 2.0 * np.pi
        window = np.clip(start - np.pi, lower, upper - 2.0 * np.pi)
        return np.where(turn, window, lower), np.where(turn, window + 2.0 * np.pi, upper)

    @staticmethod
    def _check_goal(arm: ArmModel, goal: np.ndarray) -> np.ndarray:
        g = np.array(goal, dtype=float)          # a copy: writable, as the kernels are compiled
        if g.shape != (3,):
            raise InvalidRequest(
                f'goal must be 3 coordinates (x, y, z) in metres, got shape {g.shape}')
        if not np.all(np.isfinite(g)):
            raise InvalidRequest(f'goal has a non-finite coordinate: {g.tolist()}')
        with np.errstate(over='ignore'):             # a goal of 1e308 is just far away
            dist = float(np.linalg.norm(g - arm.reach_centre))
        # the tool point at full stretch can land a rounding error beyond the links' sum
        if dist > arm.reach * (1.0 + REACH_ROUNDING):
            where = 'the base' if not arm.reach_centre.any() else 'the first joint'
            raise InvalidRequest(
                f'goal is {dist:.4f} m from {where}, '
                f"beyond the arm's reach of {arm.reach:.4f} m (eq. 14)")
        return g

    @staticmethod
    def _check_start(arm: ArmModel, start: np.ndarray) -> np.ndarray:
        try:
            q = arm.full_start(start)
        except ValueError as exc:
            raise InvalidRequest(str(exc)) from None
        if not np.all(np.isfinite(q)):
            raise InvalidRequest(f'start has a non-finite joint angle: {q.tolist()}')
        out = np.flatnonzero((q < arm.lower - 1e-9) | (q > arm.upper + 1e-9))
        if out.size:
            i = int(out[0])
            raise InvalidRequest(
                f'start joint {arm.joint_names[i]} = {q[i]:.6g} rad is outside its limits '
                f'[{arm.lower[i]:.4f}, {arm.upper[i]:.4f}]')
        return np.clip(q, arm.lower, arm.upper)

    def full(self, x: np.ndarray) -> np.ndarray:
        """Return full joint vectors (N, n_joints): x (N, planned), then the held joints."""
        x = np.atleast_2d(x)
        q = np.broadcast_to(self.start, (x.shape[0], self.arm.n_joints)).copy()
        q[:, : self.arm.planned] = x
        return q

    def tool(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return tool position and axis (N, 3) for planned-joint vectors x (N, planned)."""
        rows = tool_rows(self.chain, np.ascontiguousarray(x, dtype=float), False)
        return rows[0], rows[1]

    def tool_jacobian(self, x: np.ndarray) -> ToolJacobian:
        """Return ``ArmModel.tool_jacobian`` for planned-joint vectors x (N, planned)."""
        return ToolJacobian(tool_rows(self.chain, np.ascontiguousarray(x, dtype=float), True))

    def residuals(self, p: np.ndarray, u: np.ndarray) -> np.ndarray:
        """
        Return the constraint residuals, (N, 3 + the ``across`` components held; 3 in free mode).

        They are p - goal and, in radial mode, the components of u across the goal ray (zero
        where u = +-p / |p|, with both held; see the module docstring).
        """
        return self.linear_residuals(p - self.goal, u)

    def linear_residuals(self, dp: np.ndarray, du: np.ndarray) -> np.ndarray:
        """
        Return the change of the residuals for changes dp, du (..., N, 3) of the tool p and u.

        The residuals are linear in p and u, so this also maps their derivatives.
        """
        return np.concatenate((dp, du @ self.across_basis.T), axis=-1) if self.radial else dp

    def axis_angle(self, u: np.ndarray) -> np.ndarray:
        """Return the angle (rad) between each tool axis u (N, 3) and the goal ray p / |p|."""
        along = u @ self.ray_basis[0]
        across = np.linalg.norm(u @ self.ray_basis[1:].T, axis=1)
        return np.arctan2(across, along)

    def errors(self, p: np.ndarray, u: np.ndarray) -> np.ndarray:
        """
        Return the error of eq. (11), plus the axis angle in radial mode (see the module).

        With one component held across the goal ray (``across``), the angle of u from the plane
        that leaves it; with none, the position error alone.
        """
        return errors_eq11(np.ascontiguousarray(p), np.ascontiguousarray(u), self.goal,
                           self.ray_basis, len(self.across_basis), self.arm.reach)

    def motion_time(self, x: np.ndarray) -> np.ndarray:
        """Return R of eq. (10), max_i t_i(|x_i - start_i|), for x (N, planned)."""
        return motion_times(self.law, np.ascontiguousarray(x, dtype=float), self.planned_start)

    def __call__(self, x: np.ndarray) -> Evaluation:
        """Evaluate F for candidate planned-joint vectors x (N, planned)."""
        return Evaluation(*efficiency_eq9(
            self.problem, np.ascontiguousarray(np.atleast_2d(x), dtype=float),
            self.shaping_settings, self.longest_time))


@kernel
def efficiency_eq9(problem: Problem, x: np.ndarray, shaping: Shaping, longest_time: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Return F = R + S (eq. 9), R (eq. 10) and the error (eq. 11) at x (N, planned).

    S is ``fuzzy.shaping_eq9`` with ``RewardPunishment``'s settings; its rules take R as a
    fraction of ``longest_time``, the longest motion the limits allow (0 on an arm whose
    planned joints cannot move).
    """
    rows = tool_rows(problem.chain, x, False)
    err = errors_eq11(rows[0], rows[1], problem.goal, problem.ray, problem.across.shape[0],
                      problem.reach)
    r = motion_times(problem.law, x, problem.start)
    tau = r / longest_time if longest_time > 0.0 else np.zeros_like(r)
    return r + shaping_eq9(err, tau, shaping), r, err
