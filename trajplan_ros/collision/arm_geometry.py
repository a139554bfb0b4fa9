# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The arm's collision geometry, from the URDF's ``<collision>`` elements, built once per arm.

Every link below the base that has collision geometry is rigidly attached to one frame of the
planned chain: the child frame of the last chain joint on its path from the base (``joint``),
or the base itself (-1). Joints off the chain (a gripper's jaw) are held at 0. So a link's pose
at joint angles q is F_k(q) Rz(q_k) A_k^T O, with F_k the chain's frame of joint k before its
turn (``ArmModel.frames``), A_k the turn of z onto the joint axis (``urdf_import``) and O the
fixed origins after it (``attachment``).

For the continuous check (``free_motion``), ``reach[j, l]`` bounds how far any point of link
l is from joint j's axis, in every configuration: the lengths of the links from joint j to the
link's frame plus the farthest point of its geometry from that frame. A turn of dq_j moves no
point of the link by more than |dq_j| reach[j, l].
"""
from __future__ import annotations

from dataclasses import dataclass
import functools
import logging
import os
from pathlib import Path
from typing import NamedTuple

import numpy as np

from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.collision.shapes import MeshSource, Shape
from trajplan_ros.kinematics import ArmModel, InvalidArmModel
from trajplan_ros.kinematics.jit import inlined_kernel, kernel
from trajplan_ros.kinematics.lazy_modules import lazy
from trajplan_ros.kinematics.urdf_import import joints_between, read_urdf, to_axis

yourdfpy = lazy('yourdfpy')

__all__ = ['ArmGeometry', 'LinkFrames', 'LinkGeometry', 'poses_at']

_LOG = logging.getLogger('trajplan_ros')


@dataclass(frozen=True, eq=False)
class LinkGeometry:
    """One link's shapes, in its frame, and where it is attached to the chain."""

    name: str
    shapes: tuple[Shape, ...]
    joint: int                   # the chain joint whose child frame carries it; -1: the base
    attachment: np.ndarray       # (4, 4) from that frame to the link's frame

    def vertices(self) -> np.ndarray:
        """Return the vertices of the meshes that hold the link's shapes, in its frame."""
        return np.vstack([s.enclosing_mesh().vertices for s in self.shapes])


@dataclass(frozen=True, eq=False)
class ArmGeometry:
    """The links of an arm that have collision geometry (see the module docstring)."""

    arm: ArmModel
    links: tuple[LinkGeometry, ...]
    reach: np.ndarray            # (n_joints, links) m
    _align: np.ndarray           # (n_joints, 4, 4) A_k^T of each chain joint

    @classmethod
    def from_urdf(cls, urdf: str | os.PathLike | bytes, arm: ArmModel,
                  meshes: MeshSource | None = None) -> ArmGeometry:
        """
        Return the geometry of ``arm``'s links from a URDF (text, bytes or a file path).

        ``meshes``: where meshes may be read (default: beside a URDF file, no package lookup).
        The URDF's chain from the arm's base to its tip must have the arm's joints.
        """
        if meshes is None:
            text = isinstance(urdf, bytes) or str(urdf).lstrip().startswith('<')
            meshes = MeshSource(folder=None if text else Path(urdf).resolve().parent)
        try:
            robot = read_urdf(urdf)
            chain = joints_between(robot, arm.base_link, arm.tip_link)
        except InvalidArmModel as exc:
            raise InvalidCollisionInput(str(exc)) from None
        moving = [j for j in chain if j.type != 'fixed']
        if tuple(j.name for j in moving) != arm.joint_names:
            raise InvalidCollisionInput(
                f'the URDF chain {arm.base_link} -> {arm.tip_link} has joints '
                f"{[j.name for j in moving]}, not the arm's {list(arm.joint_names)}")
        align = np.stack([np.eye(4)] * arm.n_joints)
        for k, joint in enumerate(moving):
            axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), float)
            align[k, :3, :3] = to_axis(axis / np.linalg.norm(axis)).T
        beside: set[str] = set()
        links = _links(robot, arm, meshes, beside)
        if beside:                                   # said once per load, not once per mesh
            _LOG.warning('meshes of %s (no known package) read beside the URDF in %s',
                         ', '.join(f'package://{name}/' for name in sorted(beside)),
                         meshes.folder)
        return cls(arm, links, _reach(arm, links), align)

    def index(self, name: str) -> int:
        """Return the position of link ``name`` in ``links``."""
        return [link.name for link in self.links].index(name)

    @property
    def moving(self) -> np.ndarray:
        """Return which links a planned joint moves (only those are checked against obstacles)."""
        return np.array([0 <= link.joint for link in self.links], dtype=bool)

    def link_poses(self, q: np.ndarray) -> np.ndarray:
        """Return every link's pose at joint angles q (N, n_joints), (N, links, 4, 4)."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        return np.stack([poses_at(self.frames, row) for row in q])

    @functools.cached_property
    def frames(self) -> LinkFrames:
        """Return the chain and where each link sits on it, as ``poses_at`` takes them."""
        arm = self.arm
        return LinkFrames(arm.base, arm.rotations, arm.translations, arm.sign, arm.offset,
                          self._align, np.array([link.joint for link in self.links], np.int64),
                          np.stack([link.attachment for link in self.links]))


class LinkFrames(NamedTuple):
    """The chain (``ArmModel``'s arrays) and its links' places on it, for ``poses_at``."""

    base: np.ndarray             # (4, 4) B = F_0: the first joint's frame, before its turn
    rotations: np.ndarray        # (n, 3, 3) L_k's rotations
    translations: np.ndarray     # (n, 3) L_k's translations
    sign: np.ndarray             # (n,) theta_k = sign_k q_k + offset_k
    offset: np.ndarray           # (n,)
    align: np.ndarray            # (n, 4, 4) A_k^T: joint k's child frame from its turned frame
    joint: np.ndarray            # (links,) the joint that moves each link (-1: the base)
    attachment: np.ndarray       # (links, 4, 4) each link's frame in its joint's child frame


@inlined_kernel
def _product(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """Write the rigid transforms' product a b into out (numba's ``@`` would need SciPy)."""
    for r in range(3):
        for c in range(4):
            out[r, c] = a[r, 0] * b[0, c] + a[r, 1] * b[1, c] + a[r, 2] * b[2, c]
        out[r, 3] += a[r, 3]
    out[3, :3] = 0.0
    out[3, 3] = 1.0


@kernel
def poses_at(frames: LinkFrames, q: np.ndarray) -> np.ndarray:
    """
    Return every link's pose (links, 4, 4) at joint angles q (n,).

    The chain's child frame of joint k is F_k Rz(theta_k) A_k^T with F_0 = B and
    F_{k+1} = F_k Rz(theta_k) L_k (``ArmModel``); link l's pose is its joint's child frame (or
    the base frame, joint -1) times its attachment.
    """
    base, sign, offset, align = frames.base, frames.sign, frames.offset, frames.align
    rotations, translations = frames.rotations, frames.translations
    joint, attachment = frames.joint, frames.attachment
    n = len(q)
    child = np.empty((n, 4, 4))
    frame = base.copy()
    turned = base.copy()
    link = np.eye(4)
    for k in range(n):
        theta = sign[k] * q[k] + offset[k]
        c, s = np.cos(theta), np.sin(theta)
        turned[:3, 0] = frame[:3, 0] * c + frame[:3, 1] * s
        turned[:3, 1] = frame[:3, 1] * c - frame[:3, 0] * s
        turned[:3, 2:] = frame[:3, 2:]
        _product(turned, align[k], child[k])
        link[:3, :3] = rotations[k]
        link[:3, 3] = translations[k]
        _product(turned, link, frame)
    out = np.empty((len(joint), 4, 4))
    for i in range(len(joint)):
        _product(child[joint[i]] if joint[i] >= 0 else np.eye(4), attachment[i], out[i])
    return out


def _links(robot: yourdfpy.Robot, arm: ArmModel, meshes: MeshSource, beside: set[str]
           ) -> tuple[LinkGeometry, ...]:
    """Return the geometry of every link below the base that has any (``beside``: see load)."""
    chain_index = {name: k for k, name in enumerate(arm.joint_names)}
    out = []
    for link in robot.links:
        if not link.collisions:
            continue
        try:
            path = joints_between(robot, arm.base_link, link.name)
        except InvalidArmModel:
            continue                                            # not below the base
        joint, attachment = -1, np.eye(4)
        for step in path:
            origin = np.eye(4) if step.origin is None else np.asarray(step.origin, dtype=float)
            if step.name in chain_index:
                joint, attachment = chain_index[step.name], np.eye(4)
            else:
                attachment = attachment @ origin
        shapes = tuple(_shape(c, link.name, meshes, beside) for c in link.collisions)
        out.append(LinkGeometry(link.name, shapes, joint, attachment))
    return tuple(out)


def _shape(collision, link: str, meshes: MeshSource, beside: set[str]) -> Shape:
    """Return one ``<collision>`` element as a Shape, in its link's frame."""
    pose = np.eye(4) if collision.origin is None else np.asarray(collision.origin, dtype=float)
    g, where = collision.geometry, f'link {link!r} collision'
    if g.box is not None:
        return Shape.primitive('box', tuple(g.box.size), pose, where)
    if g.sphere is not None:
        return Shape.primitive('sphere', (g.sphere.radius,), pose, where)
    if g.cylinder is not None:
        return Shape.primitive('cylinder', (g.cylinder.length, g.cylinder.radius), pose, where)
    if g.mesh is not None:
        scale = np.ones(3) if g.mesh.scale is None else np.broadcast_to(
            np.asarray(g.mesh.scale, dtype=float), (3,))
        vertices, faces = meshes.load(g.mesh.filename, scale, beside)
        return Shape('mesh', pose, vertices=vertices, faces=faces)
    raise InvalidCollisionInput(f'{where} has no geometry')


def _reach(arm: ArmModel, links: tuple[LinkGeometry, ...]) -> np.ndarray:
    """Return reach[j, l]: the bound on link l's points' distance from joint j's axis."""
    hop = np.linalg.norm(arm.translations, axis=1)          # joint i's origin to joint i + 1's
    out = np.zeros((arm.n_joints, len(links)))
    for i, link in enumerate(links):
        if link.joint < 0:
            continue
        v = link.vertices() @ link.attachment[:3, :3].T + link.attachment[:3, 3]
        farthest = float(np.max(np.linalg.norm(v, axis=1)))
        for j in range(link.joint + 1):
            out[j, i] = np.sum(hop[j:link.joint]) + farthest
    return out
