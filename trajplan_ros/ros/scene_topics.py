# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The scene over topics: obstacles in as RViz markers, the scene and the arm's spheres out.

In, on ``collision_objects`` (visualization_msgs/MarkerArray), as RViz draws them: CUBE (scale
= the box's size), SPHERE (scale = diameter, refused unless x = y = z), CYLINDER (scale.x =
scale.y = diameter, scale.z = height). A marker is identified by (ns, id), its obstacle id is
``ns/id``; ADD (or MODIFY) puts it in, DELETE takes it out, DELETEALL takes out all of its ns,
or everything with an empty ns, as RViz does. Its frame may be any the node can pose
(``transforms.frame_pose``): it is placed in the base frame as that frame is when the message
arrives, and stays there. One bad marker refuses the whole message, with the reason, and the
scene stays as it was (``LiveScene``).

Out, on ``collision_markers`` (latched): the scene's obstacles in the base frame, and each
link's spheres (the conservative model, ``collision.spheres``) in the link's own frame, which
robot_state_publisher's TF places.
"""
from __future__ import annotations

from typing import Callable, Iterable, TYPE_CHECKING

from geometry_msgs.msg import Vector3
import numpy as np
from std_msgs.msg import ColorRGBA, Header
from trajplan_ros.collision.distances import CollisionWorld
from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.collision.scene import Obstacle, Scene
from trajplan_ros.collision.shapes import Shape
from trajplan_ros.ros.messages import pose_matrix_of, pose_msg
from visualization_msgs.msg import Marker, MarkerArray

if TYPE_CHECKING:
    from builtin_interfaces.msg import Time

__all__ = ['LiveScene', 'world_markers']

_OBSTACLE = ColorRGBA(r=0.8, g=0.3, b=0.2, a=0.5)
_SPHERES = ColorRGBA(r=0.2, g=0.6, b=0.9, a=0.3)


class LiveScene:
    """The obstacles received as markers, by id ``ns/id``, and MoveIt's world objects'."""

    def __init__(self) -> None:
        self.obstacles: dict[str, Obstacle] = {}
        self.moveit: tuple[Obstacle, ...] = ()        # ``ros.collision_objects``

    def received(self) -> tuple[Obstacle, ...]:
        """Return every obstacle received, markers' first."""
        return tuple(self.obstacles.values()) + self.moveit

    def apply(self, msg: MarkerArray,
              pose_of: Callable[[str], np.ndarray]) -> dict[str, Obstacle]:
        """
        Return the obstacles after ``msg`` (InvalidCollisionInput: none of it applied).

        ``pose_of(frame)``: the 4x4 pose of a marker's frame in the base frame now (ValueError
        for a frame it cannot pose).
        """
        out = dict(self.obstacles)
        for marker in msg.markers:
            ident = f'{marker.ns}/{marker.id}'
            if marker.action == Marker.DELETEALL:
                out = {k: v for k, v in out.items()
                       if marker.ns and not k.startswith(marker.ns + '/')}
            elif marker.action == Marker.DELETE:
                out.pop(ident, None)
            elif marker.action == Marker.ADD:
                out[ident] = _obstacle(marker, ident, pose_of)
            else:
                raise InvalidCollisionInput(f'marker {ident}: action {marker.action} is not '
                                            'ADD, DELETE or DELETEALL')
        Scene(tuple(out.values()))                         # the scene's own limits
        return out


def _obstacle(marker: Marker, ident: str, pose_of: Callable[[str], np.ndarray]) -> Obstacle:
    """Return the obstacle of an ADD marker in the base frame, or refuse it with the reason."""
    where = f'marker {ident}'
    try:
        frame = pose_of(marker.header.frame_id)
    except ValueError as exc:
        raise InvalidCollisionInput(f'{where}: {exc}') from None
    s = marker.scale
    pose = frame @ pose_matrix_of(marker.pose, where)
    if marker.type == Marker.CUBE:
        shape = Shape.primitive('box', (s.x, s.y, s.z), pose, where)
    elif marker.type == Marker.SPHERE:
        if not s.x == s.y == s.z:
            raise InvalidCollisionInput(f'{where}: a sphere needs scale x = y = z (its '
                                        f'diameter), got ({s.x}, {s.y}, {s.z})')
        shape = Shape.primitive('sphere', (s.x / 2,), pose, where)
    elif marker.type == Marker.CYLINDER:
        if s.x != s.y:
            raise InvalidCollisionInput(f'{where}: a cylinder needs scale x = y (its diameter), '
                                        f'got ({s.x}, {s.y})')
        shape = Shape.primitive('cylinder', (s.z, s.x / 2), pose, where)
    else:
        raise InvalidCollisionInput(f'{where}: type {marker.type} is not CUBE, SPHERE or '
                                    'CYLINDER')
    return Obstacle(ident, shape)


def _shape_marker(shape: Shape, header: Header, ns: str, ident: int,
                  colour: ColorRGBA) -> Marker:
    """Return the marker RViz draws for a box, sphere or cylinder."""
    d = shape.dimensions
    kind, scale = {'box': (Marker.CUBE, d),
                   'sphere': (Marker.SPHERE, (2 * d[0],) * 3),
                   'cylinder': (Marker.CYLINDER, (2 * d[-1], 2 * d[-1], d[0]))}[shape.kind]
    return Marker(header=header, ns=ns, id=ident, type=kind, action=Marker.ADD,
                  pose=pose_msg(shape.pose), color=colour,
                  scale=Vector3(x=float(scale[0]), y=float(scale[1]), z=float(scale[2])))


def world_markers(world: CollisionWorld | None, base_frame: str,
                  stamp: Time) -> MarkerArray:
    """Return the scene's and the arm's spheres' markers, after one that clears the old ones."""
    out = [Marker(header=Header(frame_id=base_frame, stamp=stamp), action=Marker.DELETEALL)]
    if world is None:
        return MarkerArray(markers=out)
    base = Header(frame_id=base_frame, stamp=stamp)
    out += [_shape_marker(o.shape, base, 'scene', i, _OBSTACLE)
            for i, o in enumerate(world.scene.obstacles)]
    spheres = world.arm.spheres
    out += list(_sphere_markers(spheres.centres, spheres.radii, spheres.first,
                                world.arm.link_names, stamp))
    return MarkerArray(markers=out)


def _sphere_markers(centres: np.ndarray, radii: np.ndarray, first: np.ndarray,
                    links: tuple[str, ...], stamp: Time) -> Iterable[Marker]:
    """Yield one SPHERE marker per sphere of the arm, in its link's frame."""
    for link, name in enumerate(links):
        header = Header(frame_id=name, stamp=stamp)
        for i in range(first[link], first[link + 1]):
            pose = np.eye(4)
            pose[:3, 3] = centres[i]
            yield _shape_marker(Shape('sphere', pose, (float(radii[i]),)), header,
                                'arm_spheres', int(i), _SPHERES)
