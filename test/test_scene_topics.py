# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The scene over topics: RViz markers in and out, without DDS."""
from geometry_msgs.msg import Point, Pose, Quaternion, Vector3
import numpy as np
import pytest
from std_msgs.msg import Header
from trajplan_ros import paper_arm
from trajplan_ros.collision.distances import ArmCollision, CollisionWorld
from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.collision.scene import Scene
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.ros.scene_topics import LiveScene, world_markers
from visualization_msgs.msg import Marker, MarkerArray

TABLE = {'id': 'table', 'type': 'box', 'dimensions': [1.2, 0.8, 0.04],
         'position': [0.3, 0.0, -0.02]}


def marker(ns: str, ident: int, kind: int, scale: tuple, action: int = Marker.ADD,
           frame: str = 'base_link') -> Marker:
    return Marker(header=Header(frame_id=frame), ns=ns, id=ident, type=kind, action=action,
                  scale=Vector3(x=scale[0], y=scale[1], z=scale[2]),
                  pose=Pose(position=Point(x=0.2, y=0.0, z=0.1), orientation=Quaternion()))


#: A camera frame 1 m above the base, turned a quarter turn about z.
CAMERA = np.array([[0.0, -1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 1.0],
                   [0.0, 0.0, 0.0, 1.0]])


def in_base(frame: str) -> np.ndarray:
    """Pose a frame as the node does: the base, the camera, and no other."""
    poses = {'base_link': np.eye(4), 'camera': CAMERA}
    if frame not in poses:
        raise ValueError(f"frame '{frame}' is not known")
    return poses[frame]


def test_a_marker_in_another_frame_is_placed_in_the_base_frame() -> None:
    placed = LiveScene().apply(MarkerArray(markers=[
        marker('cam', 1, Marker.CUBE, (0.3, 0.2, 0.02), frame='camera')]), in_base)
    np.testing.assert_allclose(placed['cam/1'].shape.pose[:3, 3], (0.0, 0.2, 1.1), atol=1e-15)
    np.testing.assert_allclose(placed['cam/1'].shape.pose[:3, :3], CAMERA[:3, :3])


def test_markers_change_the_live_scene_as_rviz_draws_them() -> None:
    live = LiveScene()
    live.obstacles = live.apply(MarkerArray(markers=[
        marker('shelf', 1, Marker.CUBE, (0.3, 0.2, 0.02)),
        marker('shelf', 2, Marker.SPHERE, (0.1, 0.1, 0.1)),
        marker('tools', 1, Marker.CYLINDER, (0.04, 0.04, 0.3))]), in_base)
    shapes = {k: (o.shape.kind, o.shape.dimensions) for k, o in live.obstacles.items()}
    assert shapes == {'shelf/1': ('box', (0.3, 0.2, 0.02)), 'shelf/2': ('sphere', (0.05,)),
                      'tools/1': ('cylinder', (0.3, 0.02))}
    after = live.apply(MarkerArray(markers=[marker('shelf', 0, 0, (0, 0, 0), Marker.DELETEALL),
                                            marker('tools', 1, 0, (0, 0, 0), Marker.DELETE)]),
                       in_base)
    assert after == {}
    assert live.apply(MarkerArray(markers=[marker('', 0, 0, (0, 0, 0), Marker.DELETEALL)]),
                      in_base) == {}


@pytest.mark.parametrize('bad, reason', [
    (marker('s', 1, Marker.SPHERE, (0.1, 0.2, 0.1)), 'x = y = z'),
    (marker('s', 1, Marker.CYLINDER, (0.1, 0.2, 0.1)), 'scale x = y'),
    (marker('s', 1, Marker.ARROW, (0.1, 0.1, 0.1)), 'not CUBE, SPHERE or CYLINDER'),
    (marker('s', 1, Marker.CUBE, (0.1, 0.0, 0.1)), 'finite and positive'),
    (marker('s', 1, Marker.CUBE, (0.1, 0.1, 0.1), frame='world'), "s/1: frame 'world' is not"),
])
def test_one_bad_marker_refuses_the_message_and_keeps_the_scene(bad: Marker, reason: str) -> None:
    live = LiveScene()
    good = marker('s', 0, Marker.CUBE, (0.1, 0.1, 0.1))
    live.obstacles = live.apply(MarkerArray(markers=[good]), in_base)
    with pytest.raises(InvalidCollisionInput, match=reason):
        live.apply(MarkerArray(markers=[marker('s', 5, Marker.CUBE, (1, 1, 1)), bad]), in_base)
    assert list(live.obstacles) == ['s/0']


def test_the_markers_out_show_the_scene_and_every_link_s_spheres() -> None:
    arm = paper_arm()
    world = CollisionWorld(ArmCollision.from_urdf(urdf_xml(arm, velocity=0.2), arm),
                           Scene.from_dict({'obstacles': [TABLE]}))
    out = world_markers(world, 'base_link', Header().stamp).markers
    assert out[0].action == Marker.DELETEALL
    table = [m for m in out if m.ns == 'scene']
    assert len(table) == 1 and table[0].type == Marker.CUBE
    assert (table[0].scale.x, table[0].scale.y, table[0].scale.z) == (1.2, 0.8, 0.04)
    spheres = [m for m in out if m.ns == 'arm_spheres']
    assert len(spheres) == len(world.arm.spheres.radii)
    assert {m.header.frame_id for m in spheres} == set(world.arm.link_names)
