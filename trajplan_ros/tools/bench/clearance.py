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

    def least(self, q: np.ndarray) -> tuple[float, str, int]:
        """Return the least distance over joint angles q (N, n), its pair and sample index."""
        links = len(self.names)
        best = (np.inf, '', -1)
        for k, row in enumerate(np.atleast_2d(q)):
            poses = self._poses(row)
            for p, (a, b) in enumerate(self.world.pairs):
                other, pose = ((self.links[b], poses[b]) if b < links
                               else (self.obstacles[b - links], np.eye(4)))
                d = self._distance(self.links[a], poses[a], other, pose)
                if d < best[0]:
                    best = (d, self.world.describe(p), k)
        return best
