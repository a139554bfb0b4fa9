# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
MoveIt's world objects (moveit_msgs/CollisionObject) as the scene's obstacles.

An object is an id with a frame, a pose and shapes: primitives (BOX, SPHERE, CYLINDER, CONE)
at ``pose * primitive_poses[i]`` and meshes (shape_msgs/Mesh triangles) at
``pose * mesh_poses[i]`` (identity where a pose is missing). Operations: ADD puts the object
in, replacing one of its id; APPEND adds its shapes to the object (ADD if there is none);
REMOVE takes it out (an empty id: every object); MOVE gives it the message's frame and pose,
its shapes unchanged. The frame may be any the node poses (a link of the robot's URDF, or a
frame tf knows: ``transforms.frame_pose``): it is placed in the base frame as that frame is
when the message arrives, and stays there. A cone, and a mesh, are held by a box (a mesh's
least oriented box, by trimesh): the plan keeps clear of the box, so of the shape inside it.
Each shape is one obstacle, ``id`` (one shape) or ``id#k``. One bad object refuses the whole
message, with the reason, and the objects stay as they were (``MoveItObjects.apply``).
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
import functools
from typing import Any, Callable

import numpy as np
from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.collision.scene import Obstacle
from trajplan_ros.collision.shapes import MAX_MESH_VERTICES, Shape
from trajplan_ros.kinematics.lazy_modules import lazy
from trajplan_ros.ros.messages import pose_matrix_of, pose_msg

trimesh = lazy('trimesh')

__all__ = ['MoveItObjects', 'PlacedObject']

#: The least side of the box that holds a flat mesh, m.
_THINNEST = 1e-4
#: shape_msgs/SolidPrimitive's types this scene takes, by number.
_PRIMITIVES = {1: 'box', 2: 'sphere', 3: 'cylinder', 4: 'cone'}


@dataclass(frozen=True)
class PlacedObject:
    """A world object as last applied, and the base frame's pose of its frame then."""

    msg: Any
    frame_pose: np.ndarray

    def in_base(self, base_frame: str) -> Any:
        """Return the object as an ADD in the base frame, where it was placed."""
        out = copy.deepcopy(self.msg)
        out.operation, out.header.frame_id = out.ADD, base_frame
        out.pose = pose_msg(self.frame_pose @ pose_matrix_of(self.msg.pose, 'object'))
        return out

    @functools.cached_property
    def obstacles(self) -> list[Obstacle]:
        """Return the object's shapes as obstacles in the base frame (built once)."""
        o = self.msg
        where = f"collision object '{o.id}'"
        for shapes, poses, kind in ((o.primitives, o.primitive_poses, 'primitive'),
                                    (o.meshes, o.mesh_poses, 'mesh')):
            if len(poses) > len(shapes):
                raise InvalidCollisionInput(f'{where}: {len(poses)} {kind} poses for '
                                            f'{len(shapes)} {kind}s')
        placed = self.frame_pose @ pose_matrix_of(o.pose, where)
        shapes = [_primitive(p, placed @ _pose_at(o.primitive_poses, i, where), f'{where} '
                             f'primitive {i + 1}') for i, p in enumerate(o.primitives)]
        shapes += [_mesh(m, placed @ _pose_at(o.mesh_poses, i, where), f'{where} mesh {i + 1}')
                   for i, m in enumerate(o.meshes)]
        if not shapes:
            raise InvalidCollisionInput(f'{where}: no primitive or mesh to add')
        if o.planes:
            raise InvalidCollisionInput(f'{where}: planes are not offered: give a box')
        name = [o.id] if len(shapes) == 1 else [f'{o.id}#{k}' for k in range(len(shapes))]
        return [Obstacle(n, s) for n, s in zip(name, shapes)]


class MoveItObjects:
    """The world objects received from MoveIt's clients, by id."""

    def __init__(self) -> None:
        self.objects: dict[str, PlacedObject] = {}

    def apply(self, messages: list[Any], to_base: Callable[[str], np.ndarray]
              ) -> dict[str, PlacedObject]:
        """
        Return the objects after ``messages`` (InvalidCollisionInput: none of them applied).

        ``to_base(frame)``: the 4x4 pose of a frame in the base frame now (ValueError for an
        unknown frame).
        """
        out = dict(self.objects)
        for msg in messages:
            where = f"collision object '{msg.id}'"
            if msg.operation == msg.REMOVE:
                if not msg.id:
                    out.clear()
                out.pop(msg.id, None)
                continue
            if not msg.id:
                raise InvalidCollisionInput('a collision object needs an id')
            frame_pose = _frame_pose(msg.header.frame_id, to_base, where)
            if msg.operation == msg.ADD or (msg.operation == msg.APPEND and msg.id not in out):
                out[msg.id] = PlacedObject(copy.deepcopy(msg), frame_pose)
            elif msg.operation == msg.APPEND:
                out[msg.id] = _appended(out[msg.id], msg, frame_pose)
            elif msg.operation == msg.MOVE:
                if msg.id not in out:
                    raise InvalidCollisionInput(f'{where}: MOVE of an object not in the scene')
                moved = copy.deepcopy(out[msg.id].msg)
                moved.header, moved.pose = msg.header, msg.pose
                out[msg.id] = PlacedObject(moved, frame_pose)
            else:
                raise InvalidCollisionInput(f'{where}: operation {msg.operation} is not ADD, '
                                            'REMOVE, APPEND or MOVE')
            out[msg.id].obstacles                         # refused now, not at a plan
        return out

    def obstacles(self, objects: dict[str, PlacedObject] | None = None) -> list[Obstacle]:
        """Return the obstacles of ``objects`` (default: those held), each shape one."""
        held = self.objects if objects is None else objects
        return [o for placed in held.values() for o in placed.obstacles]


def _appended(placed: PlacedObject, msg: Any, frame_pose: np.ndarray) -> PlacedObject:
    """Return ``placed`` with the shapes of ``msg`` added, placed where ``msg`` places them."""
    out = copy.deepcopy(placed.msg)
    into = (np.linalg.inv(placed.frame_pose @ pose_matrix_of(out.pose, 'object'))
            @ frame_pose @ pose_matrix_of(msg.pose, 'object'))
    for shapes, poses, new, new_poses in (
            (out.primitives, out.primitive_poses, msg.primitives, msg.primitive_poses),
            (out.meshes, out.mesh_poses, msg.meshes, msg.mesh_poses)):
        while len(poses) < len(shapes):                     # missing poses: identity
            poses.append(pose_msg(np.eye(4)))
        for i, shape in enumerate(new):
            shapes.append(shape)
            poses.append(pose_msg(into @ _pose_at(new_poses, i, 'object')))
    return PlacedObject(out, placed.frame_pose)


def _frame_pose(frame: str, to_base: Callable[[str], np.ndarray], where: str
                ) -> np.ndarray:
    try:
        return to_base(frame)
    except ValueError as exc:
        raise InvalidCollisionInput(f'{where}: {exc}') from None


def _pose_at(poses: Any, i: int, where: str) -> np.ndarray:
    return pose_matrix_of(poses[i], where) if i < len(poses) else np.eye(4)


def _primitive(primitive: Any, pose: np.ndarray, where: str) -> Shape:
    """Return a SolidPrimitive as a shape (a cone as the box that holds it)."""
    kind = _PRIMITIVES.get(primitive.type)
    dims = tuple(primitive.dimensions)
    if kind is None:
        raise InvalidCollisionInput(f'{where}: type {primitive.type} is not BOX, SPHERE, '
                                    'CYLINDER or CONE')
    if kind != 'cone':
        return Shape.primitive(kind, dims, pose, where)
    if len(dims) != 2:
        raise InvalidCollisionInput(f'{where}: a cone has 2 dimensions [height, radius], got '
                                    f'{list(dims)}')
    height, radius = dims                       # centred on its axis, as the box is
    return Shape.primitive('box', (2 * radius, 2 * radius, height), pose, where)


def _mesh(mesh: Any, pose: np.ndarray, where: str) -> Shape:
    """Return a shape_msgs/Mesh as the least oriented box that holds it (trimesh's)."""
    vertices = np.array([(v.x, v.y, v.z) for v in mesh.vertices], dtype=float).reshape(-1, 3)
    faces = np.array([tuple(t.vertex_indices) for t in mesh.triangles],
                     dtype=np.int64).reshape(-1, 3)
    if not len(faces) or len(vertices) > MAX_MESH_VERTICES:
        raise InvalidCollisionInput(f'{where}: {len(faces)} triangles and {len(vertices)} '
                                    f'vertices; 1 to {MAX_MESH_VERTICES} vertices are taken')
    if not np.all(np.isfinite(vertices)) or faces.min() < 0 or faces.max() >= len(vertices):
        raise InvalidCollisionInput(f'{where}: vertices must be finite and triangles index them')
    used = vertices[np.unique(faces)]
    try:
        box = trimesh.PointCloud(used).bounding_box_oriented.primitive
    except Exception:  # noqa: BLE001 - qhull on degenerate points: the axis-aligned box
        box = trimesh.PointCloud(used).bounding_box.primitive
    extents = np.maximum(np.asarray(box.extents, dtype=float), _THINNEST)
    return Shape.primitive('box', tuple(extents), pose @ np.asarray(box.transform), where)
