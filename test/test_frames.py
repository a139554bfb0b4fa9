# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Goals in any link frame of a URDF, posed by its joint angles (``kinematics.frames``)."""
from __future__ import annotations

import numpy as np
import pytest

from trajplan_ros.kinematics.frames import RobotFrames, UnknownFrame
from trajplan_ros.tools.bench.cases import PUBLISHED
import yourdfpy

#: The SO-101 under a world link, 0.1 m off and turned 90 degrees about z, as a cell places it.
WORLD = ('<link name="world"/><joint name="world_to_base" type="fixed"><parent link="world"/>'
         '<child link="base_link"/><origin xyz="0.1 0.2 0.05" rpy="0 0 1.5707963"/></joint>')


def so101_in_a_world() -> str:
    """Return the SO-101 URDF with ``WORLD`` above its base link."""
    text = PUBLISHED['so101'].urdf.read_text(encoding='utf-8')
    return text.replace('<link name="base_link"', WORLD + '<link name="base_link"', 1)


def test_every_link_is_posed_as_yourdfpy_poses_it() -> None:
    text = so101_in_a_world()
    frames = RobotFrames(text, 'base_link')
    other = yourdfpy.URDF.load(str(PUBLISHED['so101'].urdf), build_scene_graph=True,
                               load_meshes=False, load_collision_meshes=False)
    rng = np.random.default_rng(7)
    names = list(other.actuated_joint_names)
    for _ in range(5):
        q = dict(zip(names, rng.uniform(-1.5, 1.5, len(names))))
        other.update_cfg(q)
        for link in ('gripper_frame_link', 'wrist_link', 'moving_jaw_so101_v1_link'):
            expected = other.get_transform(frame_to=link, frame_from='base_link')
            np.testing.assert_allclose(frames.to_base(link, q), expected, atol=1e-12)
    world = frames.to_base('world', {})                  # the base's parent: no joint between
    np.testing.assert_allclose(world @ [0.1, 0.2, 0.05, 1.0], [0, 0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(world[:3, :3] @ [0, 1, 0], [1, 0, 0], atol=1e-6)
    assert frames.to_base('', {}) is not None and np.all(frames.to_base('base_link', {})
                                                         == np.eye(4))


def test_a_frame_the_robot_does_not_have_is_refused_naming_those_it_has() -> None:
    frames = RobotFrames(so101_in_a_world(), 'base_link')
    with pytest.raises(UnknownFrame, match="frame 'map' is not a link of the robot; known "
                                           'frames: base_link, gripper_frame_link, .*world'):
        frames.check('map')
    with pytest.raises(UnknownFrame, match="frame 'camera'"):
        frames.to_base('camera', {})
