# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The scene: obstacles in the arm's base frame, boxes, spheres and cylinders.

Each has the fields of shape_msgs/SolidPrimitive: box dimensions [x, y, z], sphere [radius],
cylinder [height, radius] (m), a position and an orientation (quaternion x, y, z, w), and
optional ``touch_links``, links allowed to touch it. A scene file is YAML:

    obstacles:
      - id: table
        type: box
        dimensions: [1.2, 0.8, 0.04]
        position: [0.3, 0.0, -0.02]
        orientation: [0, 0, 0, 1]
        touch_links: []

Every entry is checked before any is used: a bad one refuses the whole scene with a one-line
reason (``InvalidCollisionInput``), so a caller keeps its previous scene.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import os
from typing import Any, Iterable, Mapping

import numpy as np
from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.collision.shapes import Shape
from trajplan_ros.kinematics.rotations import QUATERNION_SLACK, rotation_matrix
import yaml

__all__ = ['MAX_OBSTACLES', 'Obstacle', 'Scene', 'pose_matrix']

#: Most obstacles in a scene.
MAX_OBSTACLES = 1000
#: Largest scene file read, bytes.
MAX_SCENE_BYTES = 1024 * 1024
_KEYS = {'id', 'type', 'dimensions', 'position', 'orientation', 'touch_links'}


def pose_matrix(position: Iterable[float], orientation: Iterable[float], where: str
                ) -> np.ndarray:
    """Return the 4x4 pose of a position and a quaternion (x, y, z, w), refusing bad values."""
    p = _numbers(position, 3, f'{where} position')
    x, y, z, w = _numbers(orientation, 4, f'{where} orientation')
    size = np.sqrt(x * x + y * y + z * z + w * w)
    if not abs(size - 1.0) < QUATERNION_SLACK:
        raise InvalidCollisionInput(f'{where}: orientation must be a unit quaternion (x, y, z, '
                                    f'w), its norm is {size:.6g}')
    out = np.eye(4)
    out[:3, :3] = rotation_matrix((x / size, y / size, z / size, w / size))
    out[:3, 3] = p
    return out


def _numbers(values: Any, count: int, where: str) -> np.ndarray:
    """Return ``count`` finite numbers, or refuse them."""
    try:
        out = np.array(values, dtype=float).ravel()
    except (TypeError, ValueError):
        raise InvalidCollisionInput(f'{where} must be {count} numbers, got {values!r}') from None
    if out.shape != (count,) or not np.all(np.isfinite(out)):
        raise InvalidCollisionInput(f'{where} must be {count} finite numbers, got {values!r}')
    return out


@dataclass(frozen=True, eq=False)
class Obstacle:
    """One obstacle: its id, its shape (in the base frame) and the links that may touch it."""

    id: str  # noqa: A003 (shape_msgs and MoveIt name it so)
    shape: Shape
    touch_links: frozenset[str] = frozenset()

    @classmethod
    def from_dict(cls, entry: Mapping[str, Any], where: str) -> Obstacle:
        """Return an obstacle from a scene file's entry (see the module docstring)."""
        if not isinstance(entry, Mapping):
            raise InvalidCollisionInput(f'{where} must be a mapping, got {entry!r}')
        unknown = set(entry) - _KEYS
        if unknown:
            raise InvalidCollisionInput(f'{where}: unknown keys {sorted(map(str, unknown))}; '
                                        f'use {sorted(_KEYS)}')
        ident = entry.get('id')
        if not isinstance(ident, str) or not ident:
            raise InvalidCollisionInput(f'{where}: id must be a non-empty string')
        where = f'{where} ({ident!r})'
        pose = pose_matrix(entry.get('position', (0, 0, 0)),
                           entry.get('orientation', (0, 0, 0, 1)), where)
        dims = entry.get('dimensions')
        if not isinstance(dims, (list, tuple)):
            raise InvalidCollisionInput(f'{where}: dimensions must be a list, got {dims!r}')
        shape = Shape.primitive(str(entry.get('type')), tuple(_numbers(dims, len(dims),
                                                                       f'{where} dimensions')),
                                pose, where)
        touch = entry.get('touch_links') or []
        if not isinstance(touch, (list, tuple)) or not all(isinstance(t, str) for t in touch):
            raise InvalidCollisionInput(f'{where}: touch_links must be a list of link names')
        return cls(ident, shape, frozenset(touch))

    def contains(self, point: np.ndarray) -> bool:
        """Return True when ``point`` (base frame) lies inside the obstacle."""
        inverse = np.linalg.inv(self.shape.pose)
        p = inverse[:3, :3] @ point + inverse[:3, 3]
        d = self.shape.dimensions
        if self.shape.kind == 'box':
            return bool(np.all(np.abs(p) <= 0.5 * np.asarray(d)))
        if self.shape.kind == 'sphere':
            return bool(p @ p <= d[0] ** 2)
        return bool(abs(p[2]) <= 0.5 * d[0] and np.hypot(p[0], p[1]) <= d[1])


@dataclass(frozen=True)
class Scene:
    """The obstacles around the arm, in its base frame (ids are unique)."""

    obstacles: tuple[Obstacle, ...] = field(default=())

    def __post_init__(self) -> None:
        if len(self.obstacles) > MAX_OBSTACLES:
            raise InvalidCollisionInput(f'the scene has {len(self.obstacles)} obstacles, over '
                                        f'the limit of {MAX_OBSTACLES}')
        ids = [o.id for o in self.obstacles]
        twice = sorted({i for i in ids if ids.count(i) > 1})
        if twice:
            raise InvalidCollisionInput(f'obstacle ids must be unique: {twice} repeat')

    @classmethod
    def from_dict(cls, data: Any, where: str = 'scene') -> Scene:
        """Return the scene of a parsed file: a mapping with the list ``obstacles``."""
        if data is None:
            return cls()
        if not isinstance(data, Mapping) or set(data) - {'obstacles'}:
            raise InvalidCollisionInput(f'{where} must be a mapping with the one key '
                                        "'obstacles'")
        entries = data.get('obstacles') or []
        if not isinstance(entries, list):
            raise InvalidCollisionInput(f'{where}: obstacles must be a list')
        if len(entries) > MAX_OBSTACLES:
            raise InvalidCollisionInput(f'{where} has {len(entries)} obstacles, over the limit '
                                        f'of {MAX_OBSTACLES}')
        return cls(tuple(Obstacle.from_dict(e, f'{where}: obstacle {i + 1}')
                         for i, e in enumerate(entries)))

    @classmethod
    def from_file(cls, path: str | os.PathLike) -> Scene:
        """Return the scene of a YAML file, or refuse it with a one-line reason."""
        try:
            size = os.path.getsize(path)
            if size > MAX_SCENE_BYTES:
                raise InvalidCollisionInput(f'scene file {os.fspath(path)} is {size} bytes, over '
                                            f'the {MAX_SCENE_BYTES} byte limit')
            with open(path, encoding='utf-8') as stream:
                data = yaml.safe_load(stream)
        except OSError as exc:
            raise InvalidCollisionInput(f'cannot read scene file {os.fspath(path)}: '
                                        f'{exc.strerror}') from None
        except yaml.YAMLError as exc:
            mark = getattr(exc, 'problem_mark', None)
            line = f' at line {mark.line + 1}' if mark is not None else ''
            raise InvalidCollisionInput(f'scene file {os.fspath(path)} is not YAML{line}: '
                                        f'{getattr(exc, "problem", exc)}') from None
        return cls.from_dict(data, f'scene file {os.fspath(path)}')

    def with_obstacles(self, added: Iterable[Obstacle] = (), removed: Iterable[str] = ()
                       ) -> Scene:
        """Return this scene less the ids ``removed``, with ``added`` (same id: replaced)."""
        added = tuple(added)
        gone = set(removed) | {o.id for o in added}
        return Scene(tuple(o for o in self.obstacles if o.id not in gone) + added)
