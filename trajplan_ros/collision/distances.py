# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Distances between the arm's links and to the scene: exact ones with coal, bounds on spheres.

``ArmCollision`` is built once per arm: its geometry (``arm_geometry``), its spheres
(``spheres``), the pairs to skip (``skip_pairs``) and coal's geometry of every shape (meshes as
bounding-volume hierarchies of their triangles, primitives as themselves). ``CollisionWorld``
adds a scene and the padding: the pairs to check are the links' pairs not skipped, and every
link a planned joint moves against every obstacle it may not touch (the arm stands on its
table: the base and what is fixed to it are not checked against the world).

The exact distance of a pair is coal's least distance over their shapes (negative or zero in
contact); the sphere bound (``pair_lower_bounds``) is never above it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import os
from typing import Any

import coal
import numpy as np

from trajplan_ros.collision.arm_geometry import ArmGeometry
from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.collision.scene import Scene
from trajplan_ros.collision.shapes import MeshSource, Shape
from trajplan_ros.collision.skip_pairs import computed_skip_pairs, read_srdf, SAMPLES, SkipPairs
from trajplan_ros.collision.spheres import pair_lower_bounds, SphereModel
from trajplan_ros.kinematics import ArmModel, InvalidArmModel
from trajplan_ros.kinematics.urdf_import import read_urdf

__all__ = ['ArmCollision', 'CollisionWorld', 'DEFAULT_PADDING']

#: Least clearance (m) a motion keeps, unless the caller says otherwise.
DEFAULT_PADDING = 0.01
_KINDS = {'box': 0, 'sphere': 1, 'cylinder': 2}


def _transform(pose: np.ndarray) -> coal.Transform3s:
    return coal.Transform3s(np.ascontiguousarray(pose[:3, :3]), np.ascontiguousarray(pose[:3, 3]))


def _solids(shapes: tuple[Shape, ...]) -> list[tuple[coal.CollisionGeometry, np.ndarray]]:
    return [(s.coal_geometry(), s.pose) for s in shapes]


def _placed(solids: list, pose: np.ndarray) -> list[tuple[coal.CollisionGeometry, Any]]:
    """Return solids (geometry, pose in their frame) placed by their frame's pose, for coal."""
    return [(g, _transform(pose @ p)) for g, p in solids]


def _distance(one: list, other: list) -> float:
    """Return coal's least distance between two sets of placed solids (``_placed``)."""
    best = np.inf
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    for g1, t1 in one:
        for g2, t2 in other:
            result.clear()
            best = min(best, coal.distance(g1, t1, g2, t2, request, result))
    return best


def _within(one: list, other: list, margin: float) -> bool:
    """Return True when two sets of placed solids come closer than ``margin`` (coal, exact)."""
    request, result = coal.CollisionRequest(), coal.CollisionResult()
    request.security_margin = margin
    for g1, t1 in one:
        for g2, t2 in other:
            result.clear()
            if coal.collide(g1, t1, g2, t2, request, result):
                return True
    return False


@dataclass(frozen=True, eq=False)
class ArmCollision:
    """An arm's collision model: geometry, spheres, pairs to skip and where they come from."""

    geometry: ArmGeometry
    spheres: SphereModel
    skip: SkipPairs
    skip_source: str                  # 'SRDF' or what the computed list found
    self_pairs: np.ndarray            # (P, 2) link indices of the pairs checked
    _solids: list = field(repr=False)

    @classmethod
    def from_urdf(cls, urdf: str | os.PathLike | bytes, arm: ArmModel, *,
                  meshes: MeshSource | None = None, srdf: str | bytes | None = None,
                  samples: int = SAMPLES) -> ArmCollision:
        """
        Return the collision model of ``arm`` from its URDF (``ArmGeometry.from_urdf``).

        ``srdf``: an SRDF document (text) whose disabled pairs are skipped; without one the
        pairs are computed (``computed_skip_pairs``, ``samples`` configurations).
        """
        geometry = ArmGeometry.from_urdf(urdf, arm, meshes)
        solids = [_solids(link.shapes) for link in geometry.links]
        model = cls(geometry, SphereModel.of(geometry), frozenset(), '', np.empty((0, 2), int),
                    solids)
        if srdf is not None:
            skip, source = read_srdf(srdf), 'SRDF'
        else:
            try:
                robot = read_urdf(urdf)
            except InvalidArmModel as exc:
                raise InvalidCollisionInput(str(exc)) from None
            parents = {j.child: j.parent for j in robot.joints}
            skip, reasons = computed_skip_pairs(geometry, parents.get, model.contacts, samples)
            source = 'computed: ' + ', '.join(f'{v} {k}' for k, v in reasons.items())
        names, links = [link.name for link in geometry.links], geometry.links
        # links on one frame of the chain never move against each other: never checked
        pairs = [(i, j) for i in range(len(names)) for j in range(i + 1, len(names))
                 if tuple(sorted((names[i], names[j]))) not in skip
                 and links[i].joint != links[j].joint]
        return cls(geometry, model.spheres, skip, source,
                   np.array(pairs, dtype=np.int64).reshape(-1, 2), solids)

    @property
    def link_names(self) -> tuple[str, ...]:
        """Return the names of the links with geometry, in order."""
        return tuple(link.name for link in self.geometry.links)

    def contacts(self, q: np.ndarray, pairs: np.ndarray) -> np.ndarray:
        """Return which link pairs (P, 2) are in contact at each q (N, n_joints), (N, P)."""
        nothing = (np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 4, 4)))
        out = np.zeros((len(q), len(pairs)), dtype=bool)
        for n, poses in enumerate(self.geometry.link_poses(q)):
            near = np.flatnonzero(pair_lower_bounds(
                poses, self.spheres.centres, self.spheres.radii, self.spheres.first, pairs,
                *nothing) <= 0.0)
            for p in near:
                i, j = pairs[p]
                out[n, p] = _within(_placed(self._solids[i], poses[i]),
                                    _placed(self._solids[j], poses[j]), 0.0)
        return out


@dataclass(frozen=True, eq=False)
class CollisionWorld:
    """An arm's collision model with a scene and a padding (m): what a motion must keep clear."""

    arm: ArmCollision
    scene: Scene = field(default_factory=Scene)
    padding: float = DEFAULT_PADDING

    def __post_init__(self) -> None:
        if not (np.isfinite(self.padding) and self.padding >= 0.0):
            raise InvalidCollisionInput(f'padding must be finite and at least 0 m, got '
                                        f'{self.padding}')
        links = self.arm.geometry.links
        moving = self.arm.geometry.moving
        world = [(i, len(links) + o) for o, obstacle in enumerate(self.scene.obstacles)
                 for i, link in enumerate(links)
                 if moving[i] and link.name not in obstacle.touch_links]
        put = object.__setattr__
        put(self, 'pairs', np.vstack((self.arm.self_pairs,
                                      np.array(world, dtype=np.int64).reshape(-1, 2))))
        shapes = [o.shape for o in self.scene.obstacles]
        put(self, '_kinds', np.array([_KINDS[s.kind] for s in shapes], dtype=np.int64))
        put(self, '_dims', np.array([s.dimensions + (0.0,) * (3 - len(s.dimensions))
                                     for s in shapes]).reshape(-1, 3))
        put(self, '_inverse', np.array([np.linalg.inv(s.pose) for s in shapes]).reshape(-1, 4, 4))
        put(self, '_obstacles', [_placed([(s.coal_geometry(), s.pose)], np.eye(4))
                                 for s in shapes])
        #: (P, n_joints): a turn dq moves pair p's links towards each other by at most
        #: sum_j |dq_j| sweep[p, j] (issue 29, item 4)
        put(self, 'sweep', np.array([self._sweep(a, b) for a, b in self.pairs]
                                    ).reshape(len(self.pairs), -1))

    def _sweep(self, a: int, b: int) -> np.ndarray:
        """
        Return how far a unit turn of each joint can move link a towards b.

        b is an obstacle if b >= links. Against the world, reach[j, a]; between two links,
        the joints up to the nearer one's frame move both as one, so only the joints after
        it count, by the farther link's reach.
        """
        geometry = self.arm.geometry
        if b >= len(geometry.links):
            return geometry.reach[:, a]
        near, far = sorted((a, b), key=lambda i: geometry.links[i].joint)
        out = geometry.reach[:, far].copy()
        out[:geometry.links[near].joint + 1] = 0.0
        return out

    @property
    def bound_arrays(self) -> tuple[np.ndarray, ...]:
        """Return what ``pair_lower_bounds`` takes besides poses and pairs, in its order."""
        spheres = self.arm.spheres
        return (spheres.centres, spheres.radii, spheres.first, self._kinds, self._dims,
                self._inverse)

    def lower_bounds(self, poses: np.ndarray, which: np.ndarray) -> np.ndarray:
        """Return sphere bounds of the distances of pairs ``which`` at link poses (links, 4, 4)."""
        centres, radii, first, kinds, dims, inverse = self.bound_arrays
        return pair_lower_bounds(poses, centres, radii, first, self.pairs[which], kinds, dims,
                                 inverse)

    def exact(self, poses: np.ndarray, which: np.ndarray) -> np.ndarray:
        """Return coal's distances of pairs ``which`` at link poses (links, 4, 4)."""
        placed: dict[int, list] = {}
        return np.array([_distance(*self._solids_of(poses, p, placed)) for p in which],
                        dtype=float)

    def within(self, poses: np.ndarray, pair: int, margin: float) -> bool:
        """Return True when pair ``pair`` is closer than ``margin`` (m) at link poses (exact)."""
        if margin < 0.0:                  # coal takes no negative margin: compare the distance
            return bool(self.exact(poses, np.array([pair]))[0] < margin)
        return _within(*self._solids_of(poses, pair, {}), margin)

    def _solids_of(self, poses: np.ndarray, pair: int, placed: dict[int, list]
                   ) -> tuple[list, list]:
        """Return pair ``pair``'s two sets of placed solids; links placed once into ``placed``."""
        links = len(self.arm.geometry.links)
        for link in (n for n in self.pairs[pair] if n < links and n not in placed):
            placed[link] = _placed(self.arm._solids[link], poses[link])
        a, b = self.pairs[pair]
        return placed[a], placed[b] if b < links else self._obstacles[b - links]

    def describe(self, pair: int) -> str:
        """Return a pair as 'link with link' or "link with 'obstacle'"."""
        names = self.arm.link_names
        a, b = self.pairs[pair]
        other = names[b] if b < len(names) else repr(self.scene.obstacles[b - len(names)].id)
        return f'{names[a]} with {other}'

    def obstacle_at(self, point: np.ndarray) -> str | None:
        """Return the id of an obstacle that holds ``point``, if any."""
        return next((o.id for o in self.scene.obstacles if o.contains(point)), None)
