# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The compiled forward kinematics of a serial chain (eq. 1-2), its Jacobian and its Hessian.

``walk_chain`` walks the joints from the tip towards the base for each configuration: per joint
i it applies v <- Rz(theta_i) (L_i rotation v + L_i translation) to the tool point and only
the rotation to the tool's axes (the tool axis u, and for a full orientation a second axis w
across it), with theta_i = sign_i q_i + offset_i. With the Jacobian, the columns of joint i
are born in its own frame, after its turn, as z x (tool point), z x (each axis) and z itself,
each times sign_i, and are then turned with everything else. A link rotation is applied by its
kind: none, about x only (every DH link: alpha_i), or in general.

``tool_rows`` walks a ``Chain`` (an arm's arrays as the kernels take them) and turns the result
into the base frame B.

``chain_hessian`` takes the second derivatives from those columns: joint i turns every column
of a joint j after it about its axis Z_i, so d2/dq_i dq_j = Z_i x (column j) for i <= j.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from trajplan_ros.kinematics.jit import inlined_kernel, kernel

__all__ = ['IDENTITY', 'ABOUT_X', 'GENERAL', 'Chain', 'chain_hessian', 'column', 'tool_rows',
           'walk_chain']

#: How a link rotation is applied: skipped, as a rotation about x, or as a 3x3 product.
IDENTITY, ABOUT_X, GENERAL = 0, 1, 2


@inlined_kernel
def column(vectors: int, joint: int, row: int) -> int:
    """
    Return the row of ``walk_chain``'s Jacobian that holds d(vector ``row``)/dq_``joint``.

    ``row`` 0 is the tool point, 1 .. V - 1 the axes, V the signed joint axis Z_joint; V =
    ``vectors``.
    """
    return vectors + (vectors + 1) * joint + row


@kernel
def walk_chain(q: np.ndarray, sign: np.ndarray, offset: np.ndarray, rotations: np.ndarray,
               translations: np.ndarray, kinds: np.ndarray, top: int, bottom: int,
               tail: np.ndarray, planned: int, jacobian: bool) -> np.ndarray:
    """
    Walk joints top-1 .. bottom from frame ``top`` to frame ``bottom`` (eq. 1-2).

    q (N, >= top) holds the joint angles, columns bottom..top-1 used; ``tail`` (V, 3) is the
    tool point and its V - 1 axes in frame ``top``. Returns (rows, N, 3): rows 0 .. V - 1 the
    tool point and axes and, with ``jacobian``, rows V + (V + 1) i + t, t < V, the derivatives
    of each by q_i and row V + (V + 1) i + V sign_i times joint i's axis, for each joint
    i < ``planned`` (``column``).
    """
    n, vectors = q.shape[0], tail.shape[0]
    rows = vectors + (vectors + 1) * planned if jacobian else vectors
    out = np.zeros((rows, n, 3))
    v = np.empty((rows, 3))
    for k in range(n):
        v[:] = 0.0
        v[:vectors] = tail
        live = vectors                            # rows born so far: point, axes, then columns
        for i in range(top - 1, bottom - 1, -1):
            r = rotations[i]
            if kinds[i] == ABOUT_X:               # y, z turned by alpha_i: (cos, sin) = r[1:, 1]
                c, s = r[1, 1], r[2, 1]
                for m in range(live):
                    y, z = v[m, 1], v[m, 2]
                    v[m, 1] = y * c - z * s
                    v[m, 2] = y * s + z * c
            elif kinds[i] == GENERAL:
                for m in range(live):
                    x, y, z = v[m, 0], v[m, 1], v[m, 2]
                    v[m, 0] = r[0, 0] * x + r[0, 1] * y + r[0, 2] * z
                    v[m, 1] = r[1, 0] * x + r[1, 1] * y + r[1, 2] * z
                    v[m, 2] = r[2, 0] * x + r[2, 1] * y + r[2, 2] * z
            v[0, 0] += translations[i, 0]
            v[0, 1] += translations[i, 1]
            v[0, 2] += translations[i, 2]
            theta = q[k, i] * sign[i] + offset[i]
            c, s = np.cos(theta), np.sin(theta)
            for m in range(live):                 # Rz(theta_i)
                x, y = v[m, 0], v[m, 1]
                v[m, 0] = x * c - y * s
                v[m, 1] = x * s + y * c
            if jacobian and i < planned:          # z x p, z x each axis and z, times sign_i
                col = column(vectors, i, 0)
                for m in range(vectors):
                    v[col + m, 0] = -sign[i] * v[m, 1]
                    v[col + m, 1] = sign[i] * v[m, 0]
                    v[col + m, 2] = 0.0
                v[col + vectors, 0] = 0.0
                v[col + vectors, 1] = 0.0
                v[col + vectors, 2] = sign[i]
                live = rows
        out[:, k, :] = v
    return out


class Chain(NamedTuple):
    """A serial chain as the kernels take it (``ArmModel.chain``); angles of joints < ``top``."""

    sign: np.ndarray            # (n,) +-1
    offset: np.ndarray          # (n,) rad
    rotations: np.ndarray       # (n, 3, 3) the link rotations
    translations: np.ndarray    # (n, 3) the link translations
    kinds: np.ndarray           # (n,) how each rotation is applied: IDENTITY, ABOUT_X, GENERAL
    tail: np.ndarray            # (V, 3) the tool point and its V - 1 axes in frame ``top``
    base: np.ndarray            # (4, 4) B, the first joint's frame in the base frame
    top: int                    # the joints walked: 0 .. top - 1
    planned: int                # the joints with Jacobian columns: 0 .. planned - 1


@kernel
def tool_rows(chain: Chain, q: np.ndarray, jacobian: bool) -> np.ndarray:
    """
    Return ``walk_chain``'s rows (rows, N, 3) for q (N, >= top), in the base frame B.

    Every row is turned by B's rotation, and the tool point moved by its translation.
    """
    out = walk_chain(q, chain.sign, chain.offset, chain.rotations, chain.translations,
                     chain.kinds, chain.top, 0, chain.tail, chain.planned, jacobian)
    r, t = chain.base[:3, :3], chain.base[:3, 3]
    for m in range(out.shape[0]):
        for k in range(out.shape[1]):
            x, y, z = out[m, k, 0], out[m, k, 1], out[m, k, 2]
            for a in range(3):
                out[m, k, a] = r[a, 0] * x + r[a, 1] * y + r[a, 2] * z
    for k in range(out.shape[1]):
        for a in range(3):
            out[0, k, a] += t[a]
    return out


@kernel
def chain_hessian(rows: np.ndarray, vectors: int) -> np.ndarray:
    """
    Return the second derivatives of the tool point p and axes by every pair of joints.

    ``rows`` (V + (V + 1) planned, N, 3): ``walk_chain``'s with the Jacobian, V = ``vectors``
    (the columns and the signed joint axes Z_i at ``column``). Returns (N, planned, planned,
    V, 3): [k, i, j, t] = d2 v_t/dq_i dq_j of vector t (0 the point, then the axes), Z_i x
    dv_t/dq_j for i <= j, symmetric.
    """
    planned, n = (rows.shape[0] - vectors) // (vectors + 1), rows.shape[1]
    out = np.empty((n, planned, planned, vectors, 3))
    for k in range(n):
        for i in range(planned):
            axis = column(vectors, i, vectors)
            zx, zy, zz = rows[axis, k, 0], rows[axis, k, 1], rows[axis, k, 2]
            for j in range(i, planned):
                for t in range(vectors):
                    at = column(vectors, j, t)
                    x, y, z = rows[at, k, 0], rows[at, k, 1], rows[at, k, 2]
                    out[k, i, j, t, 0] = out[k, j, i, t, 0] = zy * z - zz * y
                    out[k, i, j, t, 1] = out[k, j, i, t, 1] = zz * x - zx * z
                    out[k, i, j, t, 2] = out[k, j, i, t, 2] = zx * y - zy * x
    return out
