# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Serial revolute arm described by Denavit-Hartenberg parameters (Lv et al. 2019, eq. 1-2).

Each joint i has standard DH parameters (a_i, alpha_i, d_i) and its DH angle is
``theta_i = sign_i * q_i + offset_i``, where q is the joint angle a user commands. The paper's
arm needs this mapping (see ``kinematics.paper_arm``): its q = 0 is the upright pose. Units are SI
(metres, radians), REP 103.

Forward kinematics is vectorised over an (N, n_joints) array of configurations.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields
import os
from typing import Sequence

import numpy as np

from trajplan_ros.kinematics.errors import InvalidArmModel
from trajplan_ros.kinematics.forward import (ABOUT_X, Chain, chain_hessian, GENERAL, IDENTITY,
                                             tool_rows, walk_chain)
from trajplan_ros.kinematics.urdf_import import read_chain

__all__ = ['ArmModel', 'InvalidArmModel', 'ToolJacobian']


def _vector(name: str, values: Sequence[float], n: int) -> np.ndarray:
    arr = np.ascontiguousarray(values, dtype=float)        # one layout: one compiled walk
    if arr.shape != (n,):
        raise InvalidArmModel(f'{name} needs {n} values, got shape {arr.shape}')
    if not np.all(np.isfinite(arr)):
        raise InvalidArmModel(f'{name} has a non-finite value: {arr.tolist()}')
    return arr


@dataclass(frozen=True, eq=False)
class ToolJacobian:
    """
    Tool position p and axes, their first derivatives and the joint axes, in the base frame.

    Per planned joint i: dp/dq_i = Z_i x (p - o_i), du/dq_i = Z_i x u (each axis alike) and
    the signed joint axis Z_i (axis of joint i times its sign).

    ``rows`` is (V + (V + 1) planned, N, 3) as ``forward.walk_chain`` gives them: the point,
    the tool axis u (and a second axis w for a full orientation: V = ``vectors`` = 3), then per
    planned joint i the derivatives of each and Z_i (``forward.column``).
    """

    rows: np.ndarray
    vectors: int = 2

    @property
    def p(self) -> np.ndarray:
        """Tool position, (N, 3)."""
        return self.rows[0]

    @property
    def u(self) -> np.ndarray:
        """Tool axis, (N, 3)."""
        return self.rows[1]

    @property
    def jp(self) -> np.ndarray:
        """dp/dq, (N, 3, planned)."""
        return self._columns(0)

    @property
    def ju(self) -> np.ndarray:
        """du/dq, (N, 3, planned)."""
        return self._columns(1)

    @property
    def axes(self) -> np.ndarray:
        """Signed joint axes Z_i, (N, 3, planned)."""
        return self._columns(self.vectors)

    def jacobians(self) -> list[np.ndarray]:
        """Return dp/dq, du/dq and (with a second axis) dw/dq, each (N, 3, planned)."""
        return [self._columns(t) for t in range(self.vectors)]

    def _columns(self, row: int) -> np.ndarray:
        v = self.vectors
        return self.rows[v + row::v + 1].transpose(1, 2, 0)

    def hessian(self) -> np.ndarray:
        """
        Return the second derivatives of p and the axes by every pair of planned joints.

        (N, planned, planned, V, 3): [k, i, j, 0] = d2p/dq_i dq_j, [k, i, j, 1] = d2u/dq_i dq_j
        (``forward.chain_hessian``, compiled). Along joint directions n the second derivative
        d2/dt2 p(q + t n) is n^T H n.
        """
        return chain_hessian(self.rows, self.vectors)


def _rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_z(angle: np.ndarray) -> np.ndarray:
    """Return rotations about z, (..., 3, 3), for angles (...)."""
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(np.shape(angle) + (3, 3))
    out[..., 0, 0], out[..., 0, 1], out[..., 1, 0], out[..., 1, 1] = c, -s, s, c
    out[..., 2, 2] = 1.0
    return out


def _transform(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    out = np.zeros(rotation.shape[:-2] + (4, 4))
    out[..., :3, :3] = rotation
    out[..., :3, 3] = translation
    out[..., 3, 3] = 1.0
    return out


def _limit(name: str, values: Sequence[float], n: int) -> np.ndarray:
    arr = np.asarray(values, dtype=float)
    if arr.shape != (n,) or np.any(np.isnan(arr)):
        raise InvalidArmModel(f'{name} needs {n} values (not NaN), got {arr.tolist()}')
    return arr


def _names(joint_names: Sequence[str] | None, n: int) -> tuple[str, ...]:
    names = tuple(joint_names) if joint_names is not None else tuple(
        f'joint{i + 1}' for i in range(n))
    distinct = len(names) == n and len(set(names)) == n
    if not distinct or not all(isinstance(s, str) and s for s in names):
        raise InvalidArmModel(
            f'joint_names must be {n} distinct non-empty names, got {list(names)}')
    return names


def _rotations(name: str, values: Sequence, n: int) -> np.ndarray:
    arr = np.ascontiguousarray(values, dtype=float)
    if arr.shape != (n, 3, 3) or not np.all(np.isfinite(arr)):
        raise InvalidArmModel(f'{name} needs {n} finite 3x3 rotation matrices')
    if not np.allclose(arr @ np.swapaxes(arr, -1, -2), np.eye(3), atol=1e-9) or not np.allclose(
            np.linalg.det(arr), 1.0, atol=1e-9):
        raise InvalidArmModel(f'{name} holds a matrix that is not a rotation')
    return arr


#: How far (m per metre of reach, and rad for the axis) a trailing joint's axis may miss the
#: tool point (and the tool axis) for the joint to count as idle: turning it moves them by at
#: most twice that, far below any tolerance, and holding it leaves every pose of the planned
#: joints reachable. Vendor files give rounded angles: the UR5's tool0 axis misses the last
#: joint's axis by 5e-12 rad.
_IDLE = 1e-9


def _kind(rotation: np.ndarray) -> int:
    """Return how the walk applies a link rotation (``forward``: none, about x, general)."""
    if np.array_equal(rotation, np.eye(3)):
        return IDENTITY
    if rotation[0, 0] == 1.0 and not rotation[0, 1:].any() and not rotation[1:, 0].any():
        return ABOUT_X
    return GENERAL


@dataclass(frozen=True, eq=False)
class ArmModel:
    """
    A serial chain of revolute joints; the first ``planned`` joints are optimised, the rest held.

    The tool pose is B * Rz(theta_1) L_1 * Rz(theta_2) L_2 ... Rz(theta_n) L_n * tool, with
    theta_i = sign_i * q_i + offset_i: B is the base transform (the base frame to the first
    joint's frame, whose z axis is that joint's axis), L_i = (rotation_i, translation_i) the
    fixed transform from joint i's frame (after its turn) to the next joint's frame, or to the
    tip frame after the last joint. The tool point is ``tool_point`` and the tool axis
    ``tool_axis`` in that tip frame. Build one with ``from_dh`` (eq. 1: L_i = Tz(d_i) Tx(a_i)
    Rx(alpha_i)) or ``from_urdf`` (URDF origins and axes, fixed joints folded in).

    Attributes (arrays have one entry per joint unless said otherwise):
        rotations (n, 3, 3), translations (n, 3): the link transforms L_i (m).
        base (4, 4): the base transform B.
        tool_point, tool_axis (3,): in the tip frame (m; unit vector).
        sign, offset: theta_i = sign_i * q_i + offset_i (sign is +1 or -1).
        lower, upper: joint limits on q (rad); -inf / +inf for a continuous joint.
        velocity: each joint's velocity limit (rad/s); +inf where there is none.
        joint_names: names used in JointState / JointTrajectory messages.
        planned: how many leading joints the planner moves (2..7); the others keep their start
            angle.
        base_link, tip_link: the frames of the base and of the tip (messages' frame_id).
    """

    rotations: np.ndarray
    translations: np.ndarray
    base: np.ndarray
    tool_point: np.ndarray
    tool_axis: np.ndarray
    sign: np.ndarray
    offset: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    joint_names: tuple[str, ...]
    planned: int
    base_link: str
    tip_link: str
    _kinds: np.ndarray = field(init=False, repr=False, compare=False)
    _moving: dict[bool, ArmModel] = field(init=False, repr=False, compare=False)
    _chain: Chain = field(init=False, repr=False, compare=False)
    _reach: float = field(init=False, repr=False, compare=False)

    def __init__(self, rotations: Sequence, translations: Sequence, *,
                 base: np.ndarray | None = None, tool_point: Sequence[float] = (0.0, 0.0, 0.0),
                 tool_axis: Sequence[float] = (0.0, 0.0, 1.0),
                 sign: Sequence[float] | None = None, offset: Sequence[float] | None = None,
                 lower: Sequence[float], upper: Sequence[float],
                 velocity: Sequence[float] | None = None,
                 joint_names: Sequence[str] | None = None, planned: int | None = None,
                 base_link: str = 'base_link', tip_link: str = 'tool_link') -> None:
        n = len(translations)
        if n == 0:
            raise InvalidArmModel('the arm has no joints')
        put = object.__setattr__
        put(self, 'rotations', _rotations('rotations', rotations, n))
        put(self, 'translations', np.ascontiguousarray(translations, dtype=float))
        if self.translations.shape != (n, 3) or not np.all(np.isfinite(self.translations)):
            raise InvalidArmModel(f'translations needs {n} finite (x, y, z) vectors')
        base = np.eye(4) if base is None else np.asarray(base, dtype=float)
        if base.shape != (4, 4) or not np.all(np.isfinite(base)):
            raise InvalidArmModel('base must be a finite 4x4 transform')
        _rotations('base', base[None, :3, :3], 1)
        put(self, 'base', base)
        put(self, 'tool_point', _vector('tool_point', tool_point, 3))
        axis = _vector('tool_axis', tool_axis, 3)
        if not np.linalg.norm(axis) > 1e-9:
            raise InvalidArmModel(f'tool_axis must not be zero, got {axis.tolist()}')
        put(self, 'tool_axis', axis / np.linalg.norm(axis))
        put(self, 'sign', _vector('sign', np.ones(n) if sign is None else sign, n))
        put(self, 'offset', _vector('offset', np.zeros(n) if offset is None else offset, n))
        put(self, 'lower', _limit('lower', lower, n))
        put(self, 'upper', _limit('upper', upper, n))
        velocity = np.full(n, np.inf) if velocity is None else np.asarray(velocity, dtype=float)
        if velocity.shape != (n,) or not np.all(velocity > 0):
            raise InvalidArmModel(f'velocity needs {n} positive limits (rad/s), got '
                                  f'{velocity.tolist()}')
        put(self, 'velocity', velocity)
        if not np.all(np.abs(self.sign) == 1.0):
            raise InvalidArmModel(f'sign must be +1 or -1 per joint, got {self.sign.tolist()}')
        bad = np.flatnonzero(~(self.lower <= self.upper) | (self.lower == np.inf)
                             | (self.upper == -np.inf))
        if bad.size:
            i = int(bad[0])
            raise InvalidArmModel(
                f'joint {i + 1}: lower limit {self.lower[i]} is above upper limit {self.upper[i]}')
        put(self, 'joint_names', _names(joint_names, n))
        planned = n if planned is None else int(planned)
        if not 2 <= planned <= min(n, 7):
            raise InvalidArmModel(
                f'planned joints must be between 2 and {min(n, 7)}, got {planned}')
        put(self, 'planned', planned)
        put(self, 'base_link', str(base_link))
        put(self, 'tip_link', str(tip_link))
        put(self, '_kinds', np.array([_kind(r) for r in self.rotations], dtype=np.int64))
        put(self, '_moving', {})                 # without_idle_tail's answers, built once
        put(self, '_chain', Chain(self.sign, self.offset, self.rotations, self.translations,
                                  self._kinds, np.stack((self.tool_point, self.tool_axis)),
                                  np.ascontiguousarray(base), n, planned))
        t = np.vstack((self.translations, self.tool_point))
        put(self, '_reach', float(np.sum(np.hypot(np.hypot(t[:, 0], t[:, 1]), t[:, 2]))))
        if not self.reach < 1e6:
            raise InvalidArmModel(f'the links add up to {self.reach:.3g} m: not an arm')

    @classmethod
    def from_dh(cls, a: Sequence[float], alpha: Sequence[float], d: Sequence[float], *,
                sign: Sequence[float] | None = None, offset: Sequence[float] | None = None,
                lower: Sequence[float], upper: Sequence[float],
                velocity: Sequence[float] | None = None,
                joint_names: Sequence[str] | None = None, planned: int | None = None
                ) -> ArmModel:
        """
        Return the chain of standard DH parameters (eq. 1-2): L_i = Tz(d_i) Tx(a_i) Rx(alpha_i).

        a and d in metres, alpha in radians, one entry per joint; the tool is the last frame's
        origin and z axis.
        """
        n = len(a)
        if n == 0:
            raise InvalidArmModel('the arm has no joints')
        a, alpha, d = (_vector(k, v, n) for k, v in (('a', a), ('alpha', alpha), ('d', d)))
        translations = np.stack((a, np.zeros(n), d), axis=1)
        return cls([_rot_x(t) for t in alpha], translations, sign=sign, offset=offset,
                   lower=lower, upper=upper, velocity=velocity, joint_names=joint_names,
                   planned=planned)

    @classmethod
    def from_urdf(cls, urdf: str | os.PathLike, base_link: str | None = None,
                  tip_link: str | None = None, *, tool_offset: Sequence[float] = (0.0, 0.0, 0.0),
                  tool_axis: Sequence[float] = (0.0, 0.0, 1.0)) -> ArmModel:
        """
        Return the chain from ``base_link`` to ``tip_link`` of a URDF (XML text or a file path).

        See ``kinematics.urdf_import``: every revolute or continuous joint on the chain is
        planned; the tool point is the tip link's origin plus ``tool_offset`` (m, tip frame) and
        the tool axis ``tool_axis`` (tip frame). Raises InvalidArmModel with a one-line reason.
        """
        chain = read_chain(urdf, base_link, tip_link)
        return cls(chain.rotations, chain.translations, base=chain.base, tool_point=tool_offset,
                   tool_axis=tool_axis, lower=chain.lower, upper=chain.upper,
                   velocity=chain.velocity, joint_names=chain.joint_names,
                   base_link=chain.base_link, tip_link=chain.tip_link)

    @property
    def n_joints(self) -> int:
        """Return the number of joints in the chain."""
        return self.translations.shape[0]

    def same_as(self, other: ArmModel) -> bool:
        """Return True when ``other`` is the same arm: every field equal (arrays exactly)."""
        return all(np.array_equal(getattr(self, f.name), getattr(other, f.name))
                   for f in fields(self) if f.compare)

    @property
    def continuous(self) -> np.ndarray:
        """Return True for each joint without limits (a URDF continuous joint)."""
        return ~np.isfinite(self.lower) & ~np.isfinite(self.upper)

    @property
    def reach_centre(self) -> np.ndarray:
        """Return the first joint's origin in the base frame, the centre of the reach sphere."""
        return self.base[:3, 3].copy()

    @property
    def reach(self) -> float:
        """
        Radius of a sphere about ``reach_centre`` that contains every tool position (eq. 14).

        Rotations keep lengths, so each link moves the tool point by at most the length of its
        translation (sqrt(a_i^2 + d_i^2) for DH links) and the tool point lies within
        ``tool_point``'s length of the tip: no goal farther than the sum can be reached, whatever
        the joint angles. Computed once (the objective asks for it at every evaluation).
        """
        return self._reach

    @property
    def dh(self) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Return (a, alpha, d) when the chain is a standard DH chain (``from_dh``), else None."""
        plain = (np.array_equal(self.base, np.eye(4)) and not self.tool_point.any()
                 and np.array_equal(self.tool_axis, (0.0, 0.0, 1.0)))
        if not plain or np.any(self._kinds == GENERAL) or self.translations[:, 1].any():
            return None
        r = self.rotations
        return self.translations[:, 0], np.arctan2(r[:, 2, 1], r[:, 1, 1]), self.translations[:, 2]

    def without_idle_tail(self, axis: bool) -> ArmModel:
        """
        Return the arm with its trailing joints that cannot move the tool held (not planned).

        Joint i cannot move the tool point when the point lies on its axis whatever the joints
        after it do (they cannot move it either); with ``axis`` the tool axis must also lie
        along joint i's axis. Returns self when every planned joint can move the tool. Every
        plan asks, so the answer is kept.
        """
        if axis not in self._moving:
            self._moving[axis] = self._without_idle_tail(axis)
        return self._moving[axis]

    def _without_idle_tail(self, axis: bool) -> ArmModel:
        planned = self.planned
        point, direction = self.tool_point, self.tool_axis
        for i in range(self.n_joints - 1, 0, -1):
            point = self.rotations[i] @ point + self.translations[i]    # in joint i's frame
            direction = self.rotations[i] @ direction
            still = np.hypot(point[0], point[1]) <= _IDLE * max(1.0, self.reach)
            if axis:
                still &= np.hypot(direction[0], direction[1]) <= _IDLE
            if not still:
                break
            planned = min(planned, i)
        if planned == self.planned:
            return self
        held = ArmModel(self.rotations, self.translations, base=self.base,
                        tool_point=self.tool_point, tool_axis=self.tool_axis, sign=self.sign,
                        offset=self.offset, lower=self.lower, upper=self.upper,
                        velocity=self.velocity, joint_names=self.joint_names,
                        planned=max(planned, 2), base_link=self.base_link,
                        tip_link=self.tip_link)
        # a user plans at least two joints; with the second idle, the planner moves one
        object.__setattr__(held, 'planned', planned)
        object.__setattr__(held, '_chain', held._chain._replace(planned=planned))
        return held

    def every_joint_planned(self) -> ArmModel:
        """Return the arm with every joint planned (a joint goal moves the held ones too)."""
        if self.planned == self.n_joints:
            return self
        return ArmModel(self.rotations, self.translations, base=self.base,
                        tool_point=self.tool_point, tool_axis=self.tool_axis, sign=self.sign,
                        offset=self.offset, lower=self.lower, upper=self.upper,
                        velocity=self.velocity, joint_names=self.joint_names,
                        base_link=self.base_link, tip_link=self.tip_link)

    def speeds(self, omega: float) -> np.ndarray:
        """Return each joint's angular velocity (rad/s) at servo velocity omega."""
        return np.minimum(float(omega), self.velocity)

    def full_start(self, angles: Sequence[float]) -> np.ndarray:
        """
        Return a start as every joint's angle (rad), from all of them or the planned ones.

        A start gives every joint angle of the arm, or only the planned ones (the held joints are
        then at 0); any other count raises ValueError with the reason.
        """
        q = np.asarray(angles, dtype=float).ravel()
        if q.size == self.planned < self.n_joints:
            q = np.concatenate((q, np.zeros(self.n_joints - self.planned)))
        if q.size != self.n_joints:
            counts = (f'{self.n_joints} joint angles' if self.planned == self.n_joints else
                      f'{self.n_joints} joint angles (or the {self.planned} planned ones)')
            raise ValueError(f'a start needs {counts}, got {q.size}')
        return q

    def within_limits(self, q: np.ndarray, tol: float = 1e-12) -> np.ndarray:
        """Return True where every joint of q (..., n_joints) lies inside its limits."""
        q = np.asarray(q, dtype=float)
        return np.all((q >= self.lower - tol) & (q <= self.upper + tol), axis=-1)

    def held_tail(self, q: np.ndarray, tool: np.ndarray | None = None) -> np.ndarray:
        """
        Return the tool point and axes (V, 3) in frame ``planned``, the held joints at q.

        q holds every joint's angle (n_joints,); ``tool`` (V, 3): the point and axes in the tip
        frame (default ``tool_point`` and ``tool_axis``).

        Pass it as ``tail`` to ``tool`` and ``tool_jacobian`` to walk the planned joints only.
        """
        q = np.ascontiguousarray(q, dtype=float)[None, :]
        tool = self._chain.tail if tool is None else np.ascontiguousarray(tool, dtype=float)
        return walk_chain(q, self.sign, self.offset, self.rotations, self.translations,
                          self._kinds, self.n_joints, self.planned, tool, self.planned,
                          False)[:, 0]

    def tool(self, q: np.ndarray, tail: np.ndarray | None = None
             ) -> tuple[np.ndarray, np.ndarray]:
        """
        Return tool position (N, 3) and tool axis (N, 3) for configurations q (N, n_joints).

        With ``tail`` (from ``held_tail``), q holds the planned joints only (N, planned).
        """
        vec = self._walk(np.asarray(q, dtype=float), tail, jacobian=False)     # (2, N, 3)
        return vec[0], vec[1]

    def tool_jacobian(self, q: np.ndarray, tail: np.ndarray | None = None) -> ToolJacobian:
        """
        Return tool position and axis, their derivatives and the joint axes (``ToolJacobian``).

        ``tail`` as for ``tool``.
        """
        rows = self._walk(np.asarray(q, dtype=float), tail, jacobian=True)
        return ToolJacobian(rows, 2 if tail is None else len(tail))

    def chain(self, tail: np.ndarray | None = None) -> Chain:
        """
        Return the chain as the kernels take it (``forward.Chain``).

        Without ``tail``, every joint is walked to the tool; with ``tail`` (from ``held_tail``),
        only the planned ones, to the tool point and axis ``tail`` in frame ``planned``.
        """
        if tail is None:
            return self._chain
        return self._chain._replace(tail=np.ascontiguousarray(tail, dtype=float),
                                    top=self.planned)

    def _walk(self, q: np.ndarray, tail: np.ndarray | None, jacobian: bool) -> np.ndarray:
        return tool_rows(self.chain(tail), np.ascontiguousarray(q, dtype=float), jacobian)

    def frames(self, q: np.ndarray) -> np.ndarray:
        """
        Return the frames of the chain at q (N, n_joints), (N, n_joints + 1, 4, 4).

        Frame i < n_joints is joint i's frame before its turn (its z axis is the joint's axis,
        frame 0 is B); the last is the tool frame: the tip frame moved to the tool point. For a
        DH chain they are the DH frames 0..n.
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        turn = _transform(_rot_z(q * self.sign + self.offset), np.zeros(3))   # (N, n, 4, 4)
        link = _transform(self.rotations, self.translations)                    # (n, 4, 4)
        out = np.empty((q.shape[0], self.n_joints + 1, 4, 4))
        out[:, 0] = self.base
        for i in range(self.n_joints):
            out[:, i + 1] = out[:, i] @ turn[:, i] @ link[i]
        out[:, -1, :3, 3] += out[:, -1, :3, :3] @ self.tool_point
        return out
