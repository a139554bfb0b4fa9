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
with it turned away; written through the tool axis it holds for any chain. Mode "approach" (not
in the paper) holds the tool axis along a fixed direction d of the base frame instead of the
goal ray, e.g. d = (0, 0, -1) for a grasp from above; the rotation about the axis stays free.
Both modes hold one target direction, the axis target (``axis_target``): every formula below
is the same for either. The axis error is the angle between u_tool and the target (``axis_angle``;
a tool pointing the other way is an error of pi). Mode "pose" (not in the paper either) holds
the tool frame's whole orientation, a rotation R_goal of the base frame: the tool axis along
R_goal u0 and a second tool axis w (across u, ``second_axis``) along R_goal w0, u0 and w0 being
the two in the tip frame. Its angle error is the angle of the rotation between the goal's and
the reached orientation (``orientation_angle``). With the axis held, the error fed to S
combines both, err = sqrt(|p - goal|^2 + (L angle)^2), with L the arm's reach turning radians
into metres.

The local polish needs the constraints as smooth residuals: the position residual p - goal and,
with the axis held, the two components of u_tool across the target (``residuals``), which vanish
at u_tool = +-target; the angle tells the two apart. A pose adds w's component along
R_goal (u0 x w0), which with u on its target vanishes at w = +-R_goal w0.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import NamedTuple, Sequence

import numpy as np

from trajplan_ros.kinematics import ArmModel, ToolJacobian
from trajplan_ros.kinematics.forward import Chain, tool_rows
from trajplan_ros.kinematics.jit import inlined_kernel, kernel
from trajplan_ros.kinematics.rotations import rotation_matrix, unit_quaternion
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.motion.time_law import motion_times, TimeLaw
from trajplan_ros.search.fuzzy import RewardPunishment, Shaping, shaping_eq9
from trajplan_ros.search.goal import Goal, InvalidRequest, Mode, unit_direction

__all__ = ['Objective', 'Evaluation', 'Problem', 'direction_basis', 'errors_eq11',
           'planned_arm', 'second_axis', 'tool_angle', 'tool_angles']

#: Table 4: angular velocity of every servo, rad/s.
DEFAULT_OMEGA = 0.2
#: Relative slack of the reach check (eq. 14): the tool point of a pose at full stretch,
#: computed in floating point, can lie a few rounding errors beyond the sum of the links.
REACH_ROUNDING = 1e-9


#: Largest sine of the angle between two joint axes that counts as parallel (``pan_and_pitch``):
#: a URDF's axes are off by micro-radians.
PARALLEL = 1e-3


@dataclass(frozen=True)
class Evaluation:
    """Vectorised objective values for N candidate joint goals."""

    efficiency: np.ndarray      # F (eq. 9), s
    motion_time: np.ndarray     # R (eq. 10), s
    error: np.ndarray           # constraint error fed to S (eq. 11), m


def second_axis(tool_axis: np.ndarray) -> np.ndarray:
    """
    Return the tool's second axis w0 (tip frame), across the tool axis u0, for a full pose.

    The tip frame's x axis made perpendicular to u0 (its y axis where u0 is along x): for the
    default u0 = z, w0 = x, and (u0, w0) fix the tip frame's orientation.
    """
    u = np.asarray(tool_axis, dtype=float) / np.linalg.norm(tool_axis)
    return direction_basis(u, np.eye(3)[0] if abs(u[0]) < 0.9 else np.eye(3)[1])[1]


def direction_basis(direction: np.ndarray, hint: np.ndarray | None = None) -> np.ndarray:
    """
    Return the unit direction d / |d| and two unit vectors across it, as the rows of a 3x3 matrix.

    The first vector across is ``hint`` made perpendicular to d, or, without a usable hint, the
    horizontal z x d (x when d is vertical); the second is d times the first.
    """
    x, y, z = d = direction / np.sqrt(direction @ direction)
    side = None if hint is None else hint - (hint @ d) * d
    if side is not None and np.sqrt(side @ side) > 1e-9 * np.sqrt(hint @ hint):
        a, b, c = side / np.sqrt(side @ side)
        return np.array([[x, y, z], [a, b, c], [y * c - z * b, z * a - x * c, x * b - y * a]])
    size = np.hypot(x, y)                                 # of z x d = (-y, x, 0)
    a, b = (-y / size, x / size) if size > 1e-12 else (1.0, 0.0)
    return np.array([[x, y, z], [a, b, 0.0], [-z * b, z * a, x * b - y * a]])


def planned_arm(arm: ArmModel, mode: Mode | str) -> ArmModel:
    """
    Return ``arm`` as a plan in ``mode`` moves it.

    Trailing joints that cannot move the tool point (nor, with the axis held, the tool axis),
    such as a wrist roll about the tool axis, keep their start angle, as moving them could only
    add time (``ArmModel.without_idle_tail``). A pose needs every joint.
    """
    mode = Mode(mode)
    return arm if mode is Mode.POSE else arm.without_idle_tail(mode is not Mode.FREE)


class Problem(NamedTuple):
    """The kernels' view of an ``Objective``: its arrays, as one argument."""

    chain: Chain            # the planned joints' chain, the held ones at their start
    goal: np.ndarray        # (3,) m
    across: np.ndarray      # (h, V - 1, 3) the tool axes' components held at zero
    #                         (``across_basis``)
    ray: np.ndarray         # (3, 3) the axis target and two vectors across it (``ray_basis``)
    reach: float            # m, L of the error (``errors_eq11``)
    start: np.ndarray       # (m,) the planned joints' start angles
    law: TimeLaw            # each joint's time law: R = max_i t_i(|x_i - start_i|) (eq. 10)
    omega: float            # rad/s
    lower: np.ndarray       # (m,) the search box
    upper: np.ndarray       # (m,)


@inlined_kernel
def tool_angle(tool: np.ndarray, ray: np.ndarray, held: int) -> float:
    """
    Return the angle error (rad) of one tool (V, 3): its point, axis u and second axis w.

    ``ray``: the axis target and two unit vectors across it (rows); ``held``: how many
    components the constraints hold (``Objective.across_basis``). 3 (a pose): the angle of the
    rotation from the goal's tool frame (ray[0], ray[1], ray[2] = u0, w0, u0 x w0 turned by
    R_goal) to the reached one (u, w, u x w), atan2(|sum g x a| / 2, (sum g . a - 1) / 2);
    2: the angle between u and ray[0]; 1: u's angle from the plane that ray[1] leaves; 0: 0.
    """
    u0, u1, u2 = tool[1, 0], tool[1, 1], tool[1, 2]
    along = u0 * ray[0, 0] + u1 * ray[0, 1] + u2 * ray[0, 2]
    side = u0 * ray[1, 0] + u1 * ray[1, 1] + u2 * ray[1, 2]
    up = u0 * ray[2, 0] + u1 * ray[2, 1] + u2 * ray[2, 2]
    if held == 1:
        return np.arcsin(min(abs(side), 1.0))
    if held == 2:
        return np.arctan2(np.hypot(side, up), along)
    if held < 3:
        return 0.0
    w0, w1, w2 = tool[2, 0], tool[2, 1], tool[2, 2]
    c0, c1, c2 = u1 * w2 - u2 * w1, u2 * w0 - u0 * w2, u0 * w1 - u1 * w0     # u x w
    cosine, sx, sy, sz = -1.0, 0.0, 0.0, 0.0
    for t in range(3):                        # g: the goal frame's row t, a: the reached one's
        a0, a1, a2 = (u0, u1, u2) if t == 0 else (w0, w1, w2) if t == 1 else (c0, c1, c2)
        g0, g1, g2 = ray[t, 0], ray[t, 1], ray[t, 2]
        cosine += g0 * a0 + g1 * a1 + g2 * a2
        sx += g1 * a2 - g2 * a1
        sy += g2 * a0 - g0 * a2
        sz += g0 * a1 - g1 * a0
    return np.arctan2(0.5 * np.sqrt(sx * sx + sy * sy + sz * sz), 0.5 * cosine)


@inlined_kernel
def tool_at(rows: np.ndarray, k: int, tool: np.ndarray) -> np.ndarray:
    """Copy tool ``k`` of ``rows`` (V, N, 3) into ``tool`` (V, 3), a buffer kept across tools."""
    for t in range(rows.shape[0]):
        for a in range(3):
            tool[t, a] = rows[t, k, a]
    return tool


@kernel
def tool_angles(rows: np.ndarray, ray: np.ndarray, held: int) -> np.ndarray:
    """Return ``tool_angle`` at each of the tools ``rows`` (V, N, 3)."""
    out, tool = np.empty(rows.shape[1]), np.empty((rows.shape[0], 3))
    for k in range(rows.shape[1]):
        out[k] = tool_angle(tool_at(rows, k, tool), ray, held)
    return out


@kernel
def errors_eq11(rows: np.ndarray, goal: np.ndarray, ray: np.ndarray, held: int,
                reach: float) -> np.ndarray:
    """
    Return the error of eq. (11) at the tools ``rows`` (V, N, 3), plus the angle's.

    ``rows``: the tool points, axes u and (a pose) second axes w, as ``forward.tool_rows``
    gives them. The error adds (L angle)^2 to the squared position error, with the angle of
    ``tool_angle`` (``ray``, ``held``) and L = ``reach``.
    """
    out, tool = np.empty(rows.shape[1]), np.empty((rows.shape[0], 3))
    for k in range(rows.shape[1]):
        sq = 0.0
        for a in range(3):
            sq += (rows[0, k, a] - goal[a]) ** 2
        sq += (reach * tool_angle(tool_at(rows, k, tool), ray, held)) ** 2
        out[k] = np.sqrt(sq)
    return out


class Objective:
    """
    F = R + S for reaching ``goal`` from ``start`` with ``arm`` (planned joints only vary).

    ``goal``: a point goal in the base frame (``Goal``: its position, mode, and the mode's
    approach direction or orientation; its tolerances are the planner's, not the objective's).
    ``goal``, ``mode``, ``approach`` and ``orientation`` hold what it takes of it: the position
    (m), the mode, the unit approach direction, a pose's unit quaternion (x, y, z, w).
    ``across`` (modes but free): how many orientation residuals the constraints hold at zero:
    the tool axis's two components across the axis target, then (a pose) the second axis's;
    all of them (None: 2, or 3 for a pose), but for ``solution_curve``'s curves.
    ``start_margin``: how far (rad) a start joint may lie outside its limits (``start_notes``).
    ``profile``: the motion's profile and limits (default the paper's servo law); a profile
    that needs a limit no source gives raises ValueError.
    """

    def __init__(self, arm: ArmModel, goal: Goal, start: np.ndarray, *,
                 omega: float = DEFAULT_OMEGA, shaping: RewardPunishment | None = None,
                 across: int | None = None, profile: MotionProfile | None = None,
                 start_margin: float = 0.0) -> None:
        self.arm = arm
        self.mode = goal.mode
        self.approach = goal.approach_direction if self.mode is Mode.APPROACH else (
            unit_direction(goal.approach))
        self.orientation = self._check_orientation(goal.orientation, self.mode)
        across = self._check_across(across, self.mode)
        if not (np.isfinite(omega) and omega > 0):
            raise ValueError(f'angular velocity must be finite and positive, got {omega}')
        self.omega = float(omega)
        self.profile = profile if profile is not None else MotionProfile()
        law = self.profile.time_law(arm, self.omega)
        self.shaping = shaping if shaping is not None else RewardPunishment()
        self.goal = self._check_goal(arm, goal.position, self.mode)
        self.start_margin = float(start_margin)
        #: The full start, and one line per joint outside its limits within ``start_margin``.
        self.start, self.start_notes = self._check_start(arm, start, self.start_margin)
        #: The arm as planned (``planned_arm``).
        self.arm = arm = planned_arm(arm, self.mode)
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
        #: Rows: the axis target, then two unit vectors across it (``_target_basis``).
        self.ray_basis = self._target_basis()
        #: (h, V - 1, 3): per orientation residual, what it takes of u (and w) (``residuals``).
        #: With fewer than all, the solutions are the larger sets ``solution_curve`` follows.
        self.across_basis = self._across_basis(across)
        #: The tool in the tip frame: point, axis u0 and, where a residual takes it (a pose
        #: holding all three), the second axis w0.
        self.tool_frame = np.array([arm.tool_point, arm.tool_axis] + (
            [second_axis(arm.tool_axis)] if self.across_basis.shape[1] == 2 else []))
        self._tail = arm.held_tail(self.start, self.tool_frame)
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
            self._holding[across] = Objective(self.arm, self.as_goal(), self.start,
                                              omega=self.omega, shaping=self.shaping,
                                              across=across, profile=self.profile,
                                              start_margin=self.start_margin)
        return self._holding[across]

    def as_goal(self) -> Goal:
        """Return the goal this objective holds the tool to (as ``aimed`` left it)."""
        return Goal(self.goal, self.mode, self.approach, self.orientation)

    def aimed(self, goal: np.ndarray, target: np.ndarray) -> Objective:
        """
        Return this objective with its goal and its axis target (a pose: orientation) moved.

        ``target``: the direction the tool axis points along (radial and approach modes: the
        result is in approach mode, its target fixed wherever the goal), or a pose's unit
        quaternion; ignored in free mode. Only what depends on them is built again
        (``search.region`` moves them at every step).
        """
        out = copy.copy(self)
        out.goal = np.array(goal, dtype=float)
        if self.mode is Mode.POSE:
            out.orientation = unit_quaternion(target)
        elif self.holds_axis:
            out.mode, out.approach = Mode.APPROACH, unit_direction(target)
        out.ray_basis = out._target_basis()
        out.across_basis = out._across_basis(self._across)
        out._holding = {}
        out.problem = self.problem._replace(goal=out.goal,
                                            across=np.ascontiguousarray(out.across_basis),
                                            ray=out.ray_basis)
        return out

    def in_plane(self) -> Objective | None:
        """
        Return this goal holding only the axis component in the goal's vertical plane, or None.

        Only approach mode on a pan-and-pitch arm (``pan_and_pitch``) has one. Such an arm,
        the SO-101, cannot turn the other component at all where its axis points down (its
        pitch joints turn in that plane, its pan and roll axes lie along the axis; a URDF's
        micro-radian offsets leave it a little off), so holding both makes a singular system
        whose search ends far from the fastest pose.
        """
        if self.mode is not Mode.APPROACH or not self.pan_and_pitch():
            return None
        return self.holding(1)

    def pan_and_pitch(self) -> bool:
        """
        Return whether the planned joints are a pan, parallel pitch joints and rolls of the tool.

        That is, every planned joint after the first turns about one common axis or about the
        tool axis, at the start and at a pose 0.5 rad further on every joint (a joint's axis can
        meet the tool axis at one pose by chance; a roll's does at every pose).
        """
        poses = np.stack((self.planned_start, self.planned_start + 0.5))
        d = self.tool_jacobian(poses)
        z = d.axes.transpose(2, 0, 1)
        z = z / np.linalg.norm(z, axis=2, keepdims=True)                     # (planned, 2, 3)
        roll = np.all(np.linalg.norm(np.cross(z, d.u), axis=2) <= PARALLEL, axis=1)
        pitch = [i for i in range(1, self.arm.planned) if not roll[i]]
        return all(np.all(np.linalg.norm(np.cross(z[i], z[pitch[0]]), axis=1) <= PARALLEL)
                   for i in pitch)

    @property
    def null_directions(self) -> int:
        """Return how many directions the solutions leave free: planned joints less constraints."""
        return max(self.arm.planned - 3 - len(self.across_basis), 0)

    @property
    def holds_axis(self) -> bool:
        """Return True when the tool axis is held too (every mode but free)."""
        return self.mode is not Mode.FREE

    @property
    def axis_target(self) -> np.ndarray:
        """Return the direction the tool axis must point along (not defined in free mode)."""
        return self.ray_basis[0]

    @property
    def target_name(self) -> str:
        """Return the axis target in words, for messages."""
        return {Mode.APPROACH: 'the approach direction',
                Mode.POSE: 'the goal orientation'}.get(self.mode, 'the goal ray')

    def _target_basis(self) -> np.ndarray:
        """
        Return the axis target and two unit vectors across it (rows; identity in free mode).

        In approach mode the first across lies in the vertical plane through the goal where it
        can: the component that the pitch joints of a pan-and-pitch arm turn. For a pose they
        are the goal's tool frame: R_goal (u0, w0, u0 x w0).
        """
        if self.mode is Mode.POSE:
            u0, w0 = self.arm.tool_axis, second_axis(self.arm.tool_axis)
            return np.stack((u0, w0, np.cross(u0, w0))) @ rotation_matrix(self.orientation).T
        if not self.holds_axis:
            return np.eye(3)
        if self.mode is Mode.RADIAL:
            return direction_basis(self.goal)
        return direction_basis(self.approach,
                               np.cross(self.approach, (-self.goal[1], self.goal[0], 0.0)))

    def _across_basis(self, across: int) -> np.ndarray:
        """Return ``across_basis`` holding ``across`` residuals of the orientation."""
        if not self.holds_axis:
            return np.empty((0, 1, 3))
        ray = self.ray_basis
        if self.mode is not Mode.POSE or across < 3:      # u alone
            return np.ascontiguousarray(ray[1: 1 + across, None, :])
        rows = np.zeros((3, 2, 3))
        rows[0, 0], rows[1, 0], rows[2, 1] = ray[1], ray[2], ray[2]
        return rows

    @staticmethod
    def _check_across(across: int | None, mode: Mode) -> int:
        """Return how many orientation residuals to hold: ``across``, or all of the mode's."""
        held = 3 if mode is Mode.POSE else 2
        across = held if across is None else across
        if type(across) is not int or not 0 <= across <= held:
            raise ValueError(f'across must be 0 to {held}, got {across!r}')
        return across

    @staticmethod
    def _check_orientation(orientation: np.ndarray | Sequence[float] | None,
                           mode: Mode) -> np.ndarray | None:
        """Return a pose's orientation as a unit quaternion; InvalidRequest for a bad one."""
        if mode is not Mode.POSE:
            return None
        if orientation is None:
            raise InvalidRequest('pose mode needs an orientation (a quaternion x, y, z, w)')
        try:
            return unit_quaternion(orientation)
        except ValueError as exc:
            raise InvalidRequest(str(exc)) from None

    @staticmethod
    def _search_box(lower: np.ndarray, upper: np.ndarray,
                    start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return the search box of joints with limits lower, upper from ``start``."""
        turn = upper - lower > 2.0 * np.pi
        window = np.clip(start - np.pi, lower, upper - 2.0 * np.pi)
        return np.where(turn, window, lower), np.where(turn, window + 2.0 * np.pi, upper)

    @staticmethod
    def _check_goal(arm: ArmModel, goal: np.ndarray, mode: Mode) -> np.ndarray:
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
        if mode is Mode.RADIAL and not np.any(g):
            raise InvalidRequest('radial mode needs a goal away from the base origin: the goal '
                                 'ray of eq. (12)-(13) has no direction at the origin')
        return g

    @staticmethod
    def _check_start(arm: ArmModel, start: np.ndarray,
                     margin: float) -> tuple[np.ndarray, list[str]]:
        """
        Return the full start and its notes; InvalidRequest for a bad one or one too far out.

        A joint outside its limits by at most ``margin`` (rad; a calibrated arm's reading) is
        kept where it is, with a note: the motion to the goal, which lies within the limits,
        brings it inside.
        """
        try:
            q = arm.full_start(start)
        except ValueError as exc:
            raise InvalidRequest(str(exc)) from None
        if not np.all(np.isfinite(q)):
            raise InvalidRequest(f'start has a non-finite joint angle: {q.tolist()}')
        beyond = np.maximum(arm.lower - q, q - arm.upper)
        notes = []
        for i in np.flatnonzero(beyond > 1e-9):
            where = (f'start joint {arm.joint_names[i]} = {q[i]:.6g} rad is outside its limits '
                     f'[{arm.lower[i]:.4f}, {arm.upper[i]:.4f}]')
            if beyond[i] > margin:
                raise InvalidRequest(f'{where} by {beyond[i]:.3g} rad, more than the '
                                     f'start_limit_margin {margin:g} rad')
            notes.append(f'{where} by {beyond[i]:.3g} rad')
        return np.where(beyond > 1e-9, q, np.clip(q, arm.lower, arm.upper)), notes

    def full(self, x: np.ndarray) -> np.ndarray:
        """Return full joint vectors (N, n_joints): x (N, planned), then the held joints."""
        x = np.atleast_2d(x)
        q = np.broadcast_to(self.start, (x.shape[0], self.arm.n_joints)).copy()
        q[:, : self.arm.planned] = x
        return q

    def tool(self, x: np.ndarray) -> np.ndarray:
        """
        Return the tools (V, N, 3) at planned-joint vectors x (N, planned).

        Rows: the tool position p, the tool axis u and, for a pose, the second axis w.
        """
        return tool_rows(self.chain, np.ascontiguousarray(x, dtype=float), False)

    def tool_jacobian(self, x: np.ndarray) -> ToolJacobian:
        """Return ``ArmModel.tool_jacobian`` for planned-joint vectors x (N, planned)."""
        return ToolJacobian(tool_rows(self.chain, np.ascontiguousarray(x, dtype=float), True),
                            len(self.tool_frame))

    def residuals(self, tool: np.ndarray) -> np.ndarray:
        """
        Return the constraint residuals at ``tool`` (V, N, 3), (N, 3 + the ``across`` held).

        They are p - goal and, with the axis held, the components of u across the axis target
        (zero where u = +-target, with both held; see the module docstring), then a pose's w
        along R_goal (u0 x w0).
        """
        return self.linear_residuals(tool[0] - self.goal, *tool[1:])

    def linear_residuals(self, dp: np.ndarray, *daxes: np.ndarray) -> np.ndarray:
        """
        Return the change of the residuals for changes dp, du[, dw] (..., N, 3) of the tool.

        The residuals are linear in p and the axes, so this also maps their derivatives.
        """
        if not self.holds_axis:
            return dp
        turn = sum(d @ self.across_basis[:, t].T for t, d in enumerate(daxes))
        return np.concatenate((dp, turn), axis=-1)

    def axis_angle(self, u: np.ndarray) -> np.ndarray:
        """Return the angle (rad) between each tool axis u (N, 3) and the axis target."""
        along = u @ self.ray_basis[0]
        across = np.linalg.norm(u @ self.ray_basis[1:].T, axis=1)
        return np.arctan2(across, along)

    def angle_errors(self, tool: np.ndarray) -> np.ndarray:
        """
        Return the angle (rad) the mode holds at ``tool`` (V, N, 3) (``tool_angle``).

        The tool axis's angle to its target (radial, approach), or the angle of the rotation
        from the goal orientation (pose); NaN in free mode.
        """
        if not self.holds_axis:
            return np.full(tool.shape[1], np.nan)
        return tool_angles(np.ascontiguousarray(tool), self.ray_basis,
                           3 if self.mode is Mode.POSE else 2)

    def errors(self, tool: np.ndarray) -> np.ndarray:
        """
        Return the error of eq. (11) at ``tool`` (V, N, 3), plus the angle's (see the module).

        With fewer components held (``across``), the angle of ``tool_angle``; with none, the
        position error alone.
        """
        return errors_eq11(np.ascontiguousarray(tool), self.goal, self.ray_basis,
                           len(self.across_basis), self.arm.reach)

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
    err = errors_eq11(tool_rows(problem.chain, x, False), problem.goal, problem.ray,
                      problem.across.shape[0], problem.reach)
    r = motion_times(problem.law, x, problem.start)
    tau = r / longest_time if longest_time > 0.0 else np.zeros_like(r)
    return r + shaping_eq9(err, tau, shaping), r, err
