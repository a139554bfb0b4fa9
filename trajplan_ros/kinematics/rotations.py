# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Unit quaternions (x, y, z, w, as geometry_msgs/Quaternion) and rotation matrices."""
from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ['QUATERNION_SLACK', 'quaternion_of_turn', 'quaternions', 'rotation_matrix',
           'turn_of_quaternion', 'unit_quaternion']

#: How far from 1 a quaternion's norm may be (rounded decimals in a file or a message).
QUATERNION_SLACK = 1e-3


def unit_quaternion(values: Sequence[float]) -> np.ndarray:
    """
    Return a quaternion (x, y, z, w) normalised; ValueError with the reason for a bad one.

    Its norm must be within ``QUATERNION_SLACK`` of 1: a zero or far-off quaternion is a
    mistake, not a rotation.
    """
    try:
        q = np.array(values, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f'an orientation must be 4 numbers (x, y, z, w), got {values!r}') \
            from None
    if q.shape != (4,) or not np.all(np.isfinite(q)):
        raise ValueError(f'an orientation must be 4 finite numbers (x, y, z, w), got '
                         f'{q.tolist()}')
    size = float(np.sqrt(q @ q))
    if not abs(size - 1.0) < QUATERNION_SLACK:
        raise ValueError(f'an orientation must be a unit quaternion (x, y, z, w), its norm is '
                         f'{size:.6g}')
    return q / size


def rotation_matrix(quaternion: Sequence[float]) -> np.ndarray:
    """Return the rotation matrix (3, 3) of a unit quaternion (x, y, z, w)."""
    x, y, z, w = quaternion
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def quaternion_of_turn(turn: Sequence[float]) -> np.ndarray:
    """Return the unit quaternion (x, y, z, w) of a rotation vector (its axis times its angle)."""
    v = np.asarray(turn, dtype=float)
    angle = float(np.linalg.norm(v))
    along = v * (0.5 if angle < 1e-8 else np.sin(0.5 * angle) / angle)
    return np.append(along, np.cos(0.5 * angle))


def turn_of_quaternion(quaternion: Sequence[float]) -> np.ndarray:
    """Return the rotation vector (axis times angle, rad) of a unit quaternion (x, y, z, w)."""
    q = np.asarray(quaternion, dtype=float)
    along = float(np.linalg.norm(q[:3]))
    return q[:3] * (2.0 * np.arctan2(along, q[3]) / along) if along > 0.0 else np.zeros(3)


def quaternions(rot: np.ndarray) -> np.ndarray:
    """
    Convert rotation matrices (N, 3, 3) to unit quaternions, (N, 4) as x, y, z, w.

    Builds K = 4 q q^T (q = (w, x, y, z)) from the matrix entries and takes the row of its
    largest diagonal entry, which is well conditioned for every rotation.
    """
    m00, m11, m22 = rot[:, 0, 0], rot[:, 1, 1], rot[:, 2, 2]
    wx, wy, wz = (rot[:, 2, 1] - rot[:, 1, 2], rot[:, 0, 2] - rot[:, 2, 0],
                  rot[:, 1, 0] - rot[:, 0, 1])
    xy, xz, yz = (rot[:, 0, 1] + rot[:, 1, 0], rot[:, 0, 2] + rot[:, 2, 0],
                  rot[:, 1, 2] + rot[:, 2, 1])
    k = np.stack([
        np.stack([1 + m00 + m11 + m22, wx, wy, wz], axis=-1),
        np.stack([wx, 1 + m00 - m11 - m22, xy, xz], axis=-1),
        np.stack([wy, xy, 1 - m00 + m11 - m22, yz], axis=-1),
        np.stack([wz, xz, yz, 1 - m00 - m11 + m22], axis=-1)], axis=1)
    rows = np.arange(rot.shape[0])
    best = np.argmax(np.diagonal(k, axis1=1, axis2=2), axis=1)
    q = k[rows, best] / (2.0 * np.sqrt(k[rows, best, best]))[:, None]
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)          # w >= 0: one of the two equal quaternions
    return q[:, [1, 2, 3, 0]]
