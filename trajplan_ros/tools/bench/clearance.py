# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
An independent check of a motion's clearance: python-fcl on the real shapes, yourdfpy's poses.

Nothing of the planner's collision check is used but the list of pairs to check: the links'
poses come from yourdfpy's forward kinematics, the distances from python-fcl (FCL itself, not
coal), with meshes as triangle hierarchies and boxes, spheres and cylinders as themselves. The
bench and the tests sample a planned motion every millisecond and ask for its least distance.
``violations`` asks python-fcl only where the shapes' bounding balls (centred on each shape's
origin, of its farthest point's radius) come within the limit: elsewhere they prove it clear.
There, a mesh's convex hull (trimesh's, through SciPy's qhull; FCL's GJK) holds the mesh, so a
shape pair whose hulls keep more than the limit keeps it too, and only the other pairs are
measured on the triangles.
"""
from __future__ import annotations

import os

import numpy as np
from trajplan_ros.collision.distances import CollisionWorld
from trajplan_ros.collision.shapes import Shape
import trimesh
import yourdfpy

__all__ = ['IndependentCheck']

#: Taken off a distance between hulls: more than GJK's tolerance and qhull's rounding.
_HULL_SLACK = 1e-5


def _fcl_geometry(fcl, shape: Shape) -> object:
    """Return a shape as python-fcl geometry (``fcl``: the module, a test and bench extra)."""
    if shape.kind == 'box':
        return fcl.Box(*shape.dimensions)
    if shape.kind == 'sphere':
        return fcl.Sphere(shape.dimensions[0])
    if shape.kind == 'cylinder':
        return fcl.Cylinder(shape.dimensions[1], shape.dimensions[0])
    model = fcl.BVHModel()
    model.beginModel(len(shape.vertices), len(shape.faces))
    model.addSubModel(np.asarray(shape.vertices, dtype=float),
                      np.asarray(shape.faces, dtype=np.int32))
    model.endModel()
    return model


def _fcl_hull(fcl, shape: Shape) -> object | None:
    """Return a mesh's convex hull as python-fcl geometry (None: not a mesh, it is its own)."""
    if shape.kind != 'mesh':
        return None
    hull = trimesh.Trimesh(shape.vertices, shape.faces).convex_hull
    faces = np.hstack((np.full((len(hull.faces), 1), 3), hull.faces)).ravel()
    return fcl.Convex(np.asarray(hull.vertices, dtype=float), len(hull.faces), faces)


def _ball(shape: Shape) -> float:
    """Return the radius of the ball about a shape's origin that holds it."""
    if shape.kind == 'box':
        return float(np.linalg.norm(shape.dimensions)) / 2
    if shape.kind == 'sphere':
        return shape.dimensions[0]
    if shape.kind == 'cylinder':
        return float(np.hypot(shape.dimensions[0] / 2, shape.dimensions[1]))
    return float(np.max(np.linalg.norm(shape.vertices, axis=1)))


def _transform(fcl, pose: np.ndarray) -> object:
    return fcl.Transform(np.ascontiguousarray(pose[:3, :3]), np.ascontiguousarray(pose[:3, 3]))


class IndependentCheck:
    """The least distance of a world's pairs along sampled joint angles, by python-fcl."""

    def __init__(self, world: CollisionWorld, urdf: str | os.PathLike) -> None:
        import fcl                            # python-fcl: a test and bench extra only
        self.fcl = fcl
        self.world = world
        self.names = world.arm.link_names
        self.robot = yourdfpy.URDF.load(str(urdf), load_meshes=False,
                                        load_collision_meshes=False)
        #: each link's and obstacle's shapes: (geometry, pose in its frame, ball radius, hull)
        self.links = [[(_fcl_geometry(fcl, s), s.pose, _ball(s), _fcl_hull(fcl, s))
                       for s in link.shapes] for link in world.arm.geometry.links]
        self.obstacles = [[(_fcl_geometry(fcl, o.shape), o.shape.pose, _ball(o.shape), None)]
                          for o in world.scene.obstacles]
        self.base = world.arm.geometry.arm.base_link
        self.joints = world.arm.geometry.arm.joint_names

    def _poses(self, q: np.ndarray) -> np.ndarray:
        """Return every link's pose at each of joint angles q (N, n), (N, links, 4, 4)."""
        out = []
        for row in np.atleast_2d(q):
            self.robot.update_cfg(dict(zip(self.joints, row)))
            out.append([self.robot.get_transform(name, self.base) for name in self.names])
        return np.array(out)

    def _partner(self, b: int, poses: np.ndarray) -> tuple[list, np.ndarray]:
        """Return the shapes of a pair's second member b and its poses (N, 4, 4)."""
        links = len(self.names)
        if b < links:
            return self.links[b], poses[:, b]
        return self.obstacles[b - links], np.broadcast_to(np.eye(4), poses[:, 0].shape)

    def _distance(self, one: list, one_pose: np.ndarray, other: list,
                  other_pose: np.ndarray, limit: float = np.inf) -> float:
        """
        Return two shape sets' distance, or a bound of it above ``limit`` (their hulls').

        So the value is at most ``limit`` exactly when the distance is.
        """
        fcl, best = self.fcl, np.inf
        for g1, p1, _, h1 in one:
            t1 = _transform(fcl, one_pose @ p1)
            for g2, p2, _, h2 in other:
                t2 = _transform(fcl, other_pose @ p2)
                if np.isfinite(limit) and (h1 is not None or h2 is not None):
                    hull = fcl.distance(fcl.CollisionObject(g1 if h1 is None else h1, t1),
                                        fcl.CollisionObject(g2 if h2 is None else h2, t2),
                                        fcl.DistanceRequest(), fcl.DistanceResult())
                    if hull - _HULL_SLACK > limit:
                        best = min(best, hull - _HULL_SLACK)
                        continue
                best = min(best, fcl.distance(fcl.CollisionObject(g1, t1),
                                              fcl.CollisionObject(g2, t2),
                                              fcl.DistanceRequest(), fcl.DistanceResult()))
        return best

    def distances(self, q: np.ndarray) -> np.ndarray:
        """Return every pair's distance at joint angles q (N, n), (N, pairs)."""
        poses = self._poses(q)
        out = np.empty((len(poses), len(self.world.pairs)))
        for p, (a, b) in enumerate(self.world.pairs):
            other, other_poses = self._partner(b, poses)
            out[:, p] = [self._distance(self.links[a], poses[k, a], other, other_poses[k])
                         for k in range(len(poses))]
        return out

    def least(self, q: np.ndarray) -> tuple[float, str, int]:
        """Return the least distance over joint angles q (N, n), its pair and sample index."""
        d = self.distances(q)
        k, p = np.unravel_index(np.argmin(d), d.shape)
        return float(d[k, p]), self.world.pair_name(int(p)), int(k)

    def violations(self, q: np.ndarray, tolerance: float) -> list[str]:
        """
        Return the pairs that break the padding along q (the first sample is the start).

        A pair within the padding at the start breaks it by coming closer than its start
        distance less ``tolerance``; any other by coming within the padding.
        """
        poses, broken = self._poses(q), []
        for p, (a, b) in enumerate(self.world.pairs):
            other, other_poses = self._partner(b, poses)
            start = self._distance(self.links[a], poses[0, a], other, other_poses[0],
                                   self.world.padding)
            limit = start - tolerance if start <= self.world.padding else self.world.padding
            near = np.flatnonzero(self._ball_bounds(self.links[a], poses[:, a], other,
                                                    other_poses) <= limit)
            least = min((self._distance(self.links[a], poses[k, a], other, other_poses[k],
                                        limit) for k in near), default=np.inf)
            if least <= limit:
                broken.append(f'{self.world.pair_name(p)} at {least:.4g} m')
        return broken

    @staticmethod
    def _ball_bounds(one: list, one_poses: np.ndarray, other: list,
                     other_poses: np.ndarray) -> np.ndarray:
        """Return a lower bound of two shape sets' distance at each sample, from their balls."""
        bound = np.full(len(one_poses), np.inf)
        for _, p1, r1, _ in one:
            c1 = (one_poses @ p1)[:, :3, 3]
            for _, p2, r2, _ in other:
                c2 = (other_poses @ p2)[:, :3, 3]
                bound = np.minimum(bound, np.linalg.norm(c1 - c2, axis=1) - r1 - r2)
        return bound
