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

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

__all__ = ['ArmModel', 'InvalidArmModel', 'ToolJacobian']


class InvalidArmModel(ValueError):
    """The arm description is not a usable chain (reason in the message)."""


def _vector(name: str, values: Sequence[float], n: int) -> np.ndarray:
    arr = np.asarray(values, dtype=float)
    if arr.shape != (n,):
        raise InvalidArmModel(f'{name} needs {n} values, got shape {arr.shape}')
    if not np.all(np.isfinite(arr)):
        raise InvalidArmModel(f'{name} has a non-finite value: {arr.tolist()}')
    return arr


@dataclass(frozen=True, eq=False)
class ToolJacobian:
    """
    Tool position p and axis u, their first derivatives and the joint axes, in the base frame.

    Per planned joint i: dp/dq_i = Z_i x (p - o_i), du/dq_i = Z_i x u and the signed joint axis
    Z_i (axis of joint i times its sign).

    ``tool`` is (3, 2, N): x, y, z of p and u. ``columns`` is (3, planned, 3, N): x, y, z of
    [i, 0] = dp/dq_i, [i, 1] = du/dq_i and [i, 2] = Z_i (coordinates first, for fast
    arithmetic).
    """

    tool: np.ndarray
    columns: np.ndarray

    @property
    def p(self) -> np.ndarray:
        """Tool position, (N, 3)."""
        return self.tool[:, 0].T

    @property
    def u(self) -> np.ndarray:
        """Tool axis, (N, 3)."""
        return self.tool[:, 1].T

    @property
    def jp(self) -> np.ndarray:
        """dp/dq, (N, 3, planned)."""
        return self.columns[:, :, 0].transpose(2, 0, 1)

    @property
    def ju(self) -> np.ndarray:
        """du/dq, (N, 3, planned)."""
        return self.columns[:, :, 1].transpose(2, 0, 1)

    def curvature(self, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """
        Return the second derivatives of p and u along joint directions n (N, planned).

        They are d2/dt2 at t = 0 of p(q + t n) and u(q + t n), each (N, 3).

        The derivative of column i with respect to q_j, for j <= i (j nearer the base), is
        Z_j x J_i, so the sum over all pairs is sum_j n_j Z_j x (2 T_j - n_j J_j) with
        T_j = sum_{i >= j} n_i J_i.
        """
        weight = n.T[:, None, :]                                 # (planned, 1, N)
        turned = self.columns[:, :, 2:] * weight                 # n_j Z_j, (3, planned, 1, N)
        # regrouped by column i: sum_i n_i (2 W_i - n_i Z_i) x J_i
        # with W_i = sum_{j <= i} n_j Z_j
        a = 2.0 * turned
        for i in range(1, a.shape[1]):                           # running sum: W_i
            a[:, i] += a[:, i - 1]
        a -= turned
        jac = self.columns[:, :, :2]
        cross = a[_NEXT] * jac[_LAST] - a[_LAST] * jac[_NEXT]    # coordinates first
        second = np.einsum('cikn,in->ckn', cross, n.T)           # (3, 2, N)
        return second[:, 0].T, second[:, 1].T


_NEXT, _LAST = [1, 2, 0], [2, 0, 1]      # (a x b)_c = a_{c+1} b_{c+2} - a_{c+2} b_{c+1}
#: The tool point and axis in the last frame, as a chain walk's (w, z) tail: the origin and z.
_TOOL_FRAME = (np.zeros(2, dtype=complex), np.array([0.0, 1.0]))


@dataclass(frozen=True, eq=False)
class ArmModel:
    """
    A chain of revolute joints; the first ``planned`` joints are optimised, the rest held.

    Attributes (all arrays have one entry per joint):
        a, alpha, d: DH link length (m), twist (rad) and offset (m), transform
            T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i) (eq. 1).
        sign, offset: theta_i = sign_i * q_i + offset_i (sign is +1 or -1).
        lower, upper: joint limits on q (rad).
        joint_names: names used in JointState / JointTrajectory messages.
        planned: how many leading joints the planner moves (2..7); the others keep their start
            angle.
    """

    a: np.ndarray
    alpha: np.ndarray
    d: np.ndarray
    sign: np.ndarray
    offset: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    joint_names: tuple[str, ...]
    planned: int
    _cos_alpha: np.ndarray = field(init=False, repr=False, compare=False)
    _sin_alpha: np.ndarray = field(init=False, repr=False, compare=False)

    def __init__(self, a: Sequence[float], alpha: Sequence[float], d: Sequence[float], *,
                 sign: Sequence[float] | None = None, offset: Sequence[float] | None = None,
                 lower: Sequence[float], upper: Sequence[float],
                 joint_names: Sequence[str] | None = None, planned: int | None = None) -> None:
        n = len(a)
        if n == 0:
            raise InvalidArmModel('the arm has no joints')
        put = object.__setattr__
        put(self, 'a', _vector('a', a, n))
        put(self, 'alpha', _vector('alpha', alpha, n))
        put(self, 'd', _vector('d', d, n))
        put(self, 'sign', _vector('sign', np.ones(n) if sign is None else sign, n))
        put(self, 'offset', _vector('offset', np.zeros(n) if offset is None else offset, n))
        put(self, 'lower', _vector('lower', lower, n))
        put(self, 'upper', _vector('upper', upper, n))
        if not np.all(np.abs(self.sign) == 1.0):
            raise InvalidArmModel(f'sign must be +1 or -1 per joint, got {self.sign.tolist()}')
        bad = np.flatnonzero(self.lower > self.upper)
        if bad.size:
            i = int(bad[0])
            raise InvalidArmModel(
                f'joint {i + 1}: lower limit {self.lower[i]} is above upper limit {self.upper[i]}')
        names = tuple(joint_names) if joint_names is not None else tuple(
            f'joint{i + 1}' for i in range(n))
        distinct = len(names) == n and len(set(names)) == n
        if not distinct or not all(isinstance(s, str) and s for s in names):
            raise InvalidArmModel(
                f'joint_names must be {n} distinct non-empty names, got {list(names)}')
        put(self, 'joint_names', names)
        planned = n if planned is None else int(planned)
        if not 2 <= planned <= min(n, 7):
            raise InvalidArmModel(
                f'planned joints must be between 2 and {min(n, 7)}, got {planned}')
        put(self, 'planned', planned)
        put(self, '_cos_alpha', np.cos(self.alpha))
        put(self, '_sin_alpha', np.sin(self.alpha))

    @property
    def n_joints(self) -> int:
        """Return the number of joints in the chain."""
        return self.a.size

    @property
    def reach(self) -> float:
        """
        Radius of a sphere about the base origin that contains every tool position (eq. 14).

        Each link moves the tool point by at most sqrt(a_i^2 + d_i^2), so no goal farther than
        the sum can be reached, whatever the joint angles.
        """
        return float(np.sum(np.hypot(self.a, self.d)))

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

    def held_tail(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """
        Return the tool point and axis in frame ``planned``, the held joints at q (n_joints,).

        Pass it as ``tail`` to ``tool`` and ``tool_jacobian`` to walk the planned joints only.
        """
        q = np.asarray(q, dtype=float)[None, :]
        w, z = self._chain(q, self.n_joints, self.planned, _TOOL_FRAME, jacobian=False)
        return w[:, 0], z[:, 0]

    def tool(self, q: np.ndarray, tail: tuple[np.ndarray, np.ndarray] | None = None
             ) -> tuple[np.ndarray, np.ndarray]:
        """
        Return tool position (N, 3) and tool z axis (N, 3) for configurations q (N, n_joints).

        With ``tail`` (from ``held_tail``), q holds the planned joints only (N, planned).
        """
        w, z = self._walk(np.asarray(q, dtype=float), tail, jacobian=False)
        vec = np.stack((w.real, w.imag, z), axis=-1)               # (2, N, 3)
        return vec[0], vec[1]

    def tool_jacobian(self, q: np.ndarray, tail: tuple[np.ndarray, np.ndarray] | None = None
                      ) -> ToolJacobian:
        """
        Return tool position and axis, their derivatives and the joint axes (``ToolJacobian``).

        ``tail`` as for ``tool``.
        """
        w, z = self._walk(np.asarray(q, dtype=float), tail, jacobian=True)
        vec = np.stack((w.real, w.imag, z))                         # (3, 2 + 3 planned, N)
        return ToolJacobian(vec[:, :2], vec[:, 2:].reshape(3, self.planned, 3, -1))

    def _walk(self, q: np.ndarray, tail: tuple[np.ndarray, np.ndarray] | None,
              jacobian: bool) -> tuple[np.ndarray, np.ndarray]:
        if tail is None:
            return self._chain(q, self.n_joints, 0, _TOOL_FRAME, jacobian)
        return self._chain(q, self.planned, 0, tail, jacobian)

    def _chain(self, q: np.ndarray, top: int, bottom: int, tail: tuple[np.ndarray, np.ndarray],
               jacobian: bool) -> tuple[np.ndarray, np.ndarray]:
        """
        Walk joints top-1 .. bottom from frame ``top`` towards the base.

        This is every optimiser's hot path.

        ``tail`` is the tool point and axis in frame ``top`` as (w, z) with w = x + i y
        (complex) and z, each of length 2. Returns w and z, each (rows, N): row 0 is the tool
        point, row 1 the tool axis and, with ``jacobian``, rows 2 + 3i, 3 + 3i and 4 + 3i are
        d(point)/dq_i, d(axis)/dq_i and sign_i times the axis of joint i, for each planned
        joint i. Per joint it applies
        v <- Rz(theta) (Rx(alpha) v + (a, 0, d)) (eq. 1) to every row at once (the translation
        only to the point), the rotation about z as one complex product, so the cost is a few
        array operations per joint whatever N is. The rows for joint i are born in its own
        frame as z x v (i v in complex form) and z, then rotated with everything else.
        q: (N, top) joint angles; columns bottom..top-1 are used.
        """
        theta = (q[:, bottom:top] * self.sign[bottom:top] + self.offset[bottom:top]).T
        rot = np.empty(theta.shape, dtype=complex)    # e^(i theta): cos, sin beat complex exp
        np.cos(theta, out=rot.real)
        np.sin(theta, out=rot.imag)
        rows = 2 + 3 * self.planned if jacobian else 2
        w = np.zeros((rows, q.shape[0]), dtype=complex)
        z = np.zeros((rows, q.shape[0]))
        w[:2] = tail[0][:, None]
        z[:2] = tail[1][:, None]
        for i in range(top - 1, bottom - 1, -1):
            ca, sa = self._cos_alpha[i], self._sin_alpha[i]
            if sa != 0.0 or ca != 1.0:
                y = w.imag.copy()
                w.imag = ca * y - sa * z
                z = sa * y + ca * z
            w[0] += self.a[i]
            z[0] += self.d[i]
            w *= rot[i - bottom]
            if jacobian and i < self.planned:
                w[2 + 3 * i: 4 + 3 * i] = (1j * self.sign[i]) * w[:2]
                z[4 + 3 * i] = self.sign[i]
        return w, z

    def frames(self, q: np.ndarray) -> np.ndarray:
        """Return every frame's homogeneous transform, (N, n_joints + 1, 4, 4); 0 is the base."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        theta = q * self.sign + self.offset
        ct, st = np.cos(theta), np.sin(theta)
        n = q.shape[0]
        link = np.zeros((n, self.n_joints, 4, 4))
        ca, sa = self._cos_alpha, self._sin_alpha
        link[..., 0, 0] = ct
        link[..., 0, 1] = -st * ca
        link[..., 0, 2] = st * sa
        link[..., 0, 3] = self.a * ct
        link[..., 1, 0] = st
        link[..., 1, 1] = ct * ca
        link[..., 1, 2] = -ct * sa
        link[..., 1, 3] = self.a * st
        link[..., 2, 1] = sa
        link[..., 2, 2] = ca
        link[..., 2, 3] = self.d
        link[..., 3, 3] = 1.0
        out = np.empty((n, self.n_joints + 1, 4, 4))
        out[:, 0] = np.eye(4)
        for i in range(self.n_joints):
            out[:, i + 1] = out[:, i] @ link[:, i]
        return out
