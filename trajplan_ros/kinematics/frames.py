# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Every link frame of a robot's URDF, posed by its joint angles: goals given in any of them.

A goal stamped in a link frame (RViz's fixed frame ``world`` above ``base_link``, a camera's
mount link, the tool) is brought into the planning base frame by the robot's own forward
kinematics at its current joint angles, without tf: ``RobotFrames.to_base``. Joints without an
angle (a gripper the node does not plan) are taken at 0.
"""
from __future__ import annotations

import os
from typing import Mapping

import numpy as np

from trajplan_ros.kinematics.urdf_import import _parents, read_urdf

__all__ = ['RobotFrames', 'UnknownFrame']


class UnknownFrame(ValueError):
    """A frame the robot's URDF does not have (the message names those it has)."""


class RobotFrames:
    """The link frames of a URDF and the transform of each into ``base_frame``."""

    def __init__(self, urdf: str | os.PathLike | bytes, base_frame: str) -> None:
        robot = read_urdf(urdf)
        self._parents = _parents(robot)
        #: Every link of the URDF, sorted.
        self.links = tuple(sorted(link.name for link in robot.links))
        if base_frame not in self.links:
            raise UnknownFrame(self._unknown(base_frame))
        self.base_frame = base_frame

    def _unknown(self, frame: str) -> str:
        return f"frame '{frame}' is not a link of the robot; known frames: {', '.join(self.links)}"

    def check(self, frame: str) -> None:
        """Raise UnknownFrame unless ``frame`` is a link of the robot (or empty: the base)."""
        if frame and frame not in self.links:
            raise UnknownFrame(self._unknown(frame))

    def to_base(self, frame: str, positions: Mapping[str, float]) -> np.ndarray:
        """Return the 4x4 pose of ``frame`` in the base frame at joint ``positions`` (rad, m)."""
        self.check(frame)
        if not frame or frame == self.base_frame:
            return np.eye(4)
        return np.linalg.solve(self._in_root(self.base_frame, positions),
                               self._in_root(frame, positions))

    def _in_root(self, link: str, positions: Mapping[str, float]) -> np.ndarray:
        """Return the pose of ``link`` in the URDF's root link frame."""
        pose = np.eye(4)
        while link in self._parents:
            joint = self._parents[link]
            origin = np.eye(4) if joint.origin is None else joint.origin
            pose = origin @ _joint_motion(joint.type, joint.axis,
                                          float(positions.get(joint.name, 0.0))) @ pose
            link = joint.parent
        return pose


def _joint_motion(kind: str, axis: np.ndarray | None, value: float) -> np.ndarray:
    """Return a joint's motion at ``value``: a turn about its axis, a slide along it, or none."""
    motion = np.eye(4)
    if kind not in ('revolute', 'continuous', 'prismatic'):
        return motion
    u = np.array([1.0, 0.0, 0.0] if axis is None else axis, dtype=float)
    u = u / np.linalg.norm(u)
    if kind != 'prismatic':
        k = np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])
        motion[:3, :3] = np.eye(3) + np.sin(value) * k + (1.0 - np.cos(value)) * k @ k
    else:
        motion[:3, 3] = value * u
    return motion
