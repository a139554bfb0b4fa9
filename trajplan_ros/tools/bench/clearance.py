# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
An independent check of a motion's clearance: python-fcl on the real shapes, yourdfpy's poses.

Nothing of the planner's collision check is used but the list of pairs to check: the links'
poses come from yourdfpy's forward kinematics, the distances from python-fcl (FCL itself, not
coal), with meshes as triangle hierarchies and boxes, spheres and cylinders as themselves. The
bench and the tests sample a planned motion every millisecond and ask for its least distance.
"""
from __future__ import annotations

import os

import numpy as np
from trajplan_ros.collision.distances import CollisionWorld
from trajplan_ros.collision.shapes import Shape
import yourdfpy

__all__ = ['IndependentCheck']


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
        self.links = [[(_fcl_geometry(fcl, s), s.pose) for s in link.shapes]
                      for link in world.arm.geometry.links]
        self.obstacles = [[(_fcl_geometry(fcl, o.shape), o.shape.pose)]
                          for o in world.scene.obstacles]
        self.base = world.arm.geometry.arm.base_link
        self.joints = world.arm.geometry.arm.joint_names

    def _poses(self, q: np.ndarray) -> list[np.ndarray]:
        self.robot.update_cfg(dict(zip(self.joints, q)))
        return [self.robot.get_transform(name, self.base) for name in self.names]

    def _distance(self, one: list, one_pose: np.ndarray, other: list,
                  other_pose: np.ndarray) -> float:
        fcl, best = self.fcl, np.inf
        for g1, p1 in one:
            o1 = fcl.CollisionObject(g1, _transform(fcl, one_pose @ p1))
            for g2, p2 in other:
                o2 = fcl.CollisionObject(g2, _transform(fcl, other_pose @ p2))
                result = fcl.DistanceResult()
                best = min(best, fcl.distance(o1, o2, fcl.DistanceRequest(), result))
        return best

    def distances(self, q: np.ndarray) -> np.ndarray:
        """Return every pair's distance at joint angles q (N, n), (N, pairs)."""
        links = len(self.names)
        out = np.empty((len(np.atleast_2d(q)), len(self.world.pairs)))
        for k, row in enumerate(np.atleast_2d(q)):
            poses = self._poses(row)
            for p, (a, b) in enumerate(self.world.pairs):
                other, pose = ((self.links[b], poses[b]) if b < links
                               else (self.obstacles[b - links], np.eye(4)))
                out[k, p] = self._distance(self.links[a], poses[a], other, pose)
        return out

    def least(self, q: np.ndarray) -> tuple[float, str, int]:
        """Return the least distance over joint angles q (N, n), its pair and sample index."""
        d = self.distances(q)
        k, p = np.unravel_index(np.argmin(d), d.shape)
        return float(d[k, p]), self.world.describe(int(p)), int(k)

    def violations(self, q: np.ndarray, tolerance: float) -> list[str]:
        """
        Return the pairs that break the padding along q (the first sample is the start).

        A pair within the padding at the start breaks it by coming closer than its start
        distance less ``tolerance``; any other by coming within the padding.
        """
        d = self.distances(q)
        limit = np.where(d[0] <= self.world.padding, d[0] - tolerance, self.world.padding)
        return [f'{self.world.describe(p)} at {d[:, p].min():.4g} m'
                for p in np.flatnonzero(d.min(axis=0) <= limit)]
