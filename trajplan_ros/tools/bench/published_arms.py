# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Published arm URDFs that the bench and the tests plan for, from the example-robot-data wheel.

The files are the vendors' own (with their warts: xacro leftovers in names, grippers on side
branches, ``package://`` meshes); nothing here copies or edits them. Each entry names the chain
the bench uses: base link, tip link and how many revolute joints lie between.
"""
from __future__ import annotations

from dataclasses import dataclass
import importlib.metadata
from pathlib import Path

__all__ = ['PUBLISHED', 'PublishedArm', 'robots_dir']


@dataclass(frozen=True)
class PublishedArm:
    """One arm: its URDF below ``robots_dir()``, the chain from ``base_link`` to ``tip_link``."""

    path: str
    base_link: str
    tip_link: str
    joints: int

    @property
    def urdf(self) -> Path:
        """Return the URDF file's path."""
        return robots_dir() / self.path


PUBLISHED = {
    'so101': PublishedArm('so_arm_description/urdf/so101.urdf', 'base_link',
                          'gripper_frame_link', 5),
    'ur5': PublishedArm('ur_description/urdf/ur5_robot.urdf', 'base_link', 'tool0', 6),
    'xarm7': PublishedArm('xarm_description/urdf/xarm7.urdf', 'link_base', 'link_eef', 7),
    'panda': PublishedArm('panda_description/urdf/panda.urdf', 'panda_link0', 'panda_hand_tcp',
                          7),
    'kinova': PublishedArm('kinova_description/robots/kinova.urdf', 'base',
                           'j2s6s200_end_effector', 6),
}


def robots_dir() -> Path:
    """Return the example-robot-data robots folder (the wheel is a test and bench extra)."""
    try:
        dist = importlib.metadata.distribution('example-robot-data')
    except importlib.metadata.PackageNotFoundError:
        raise FileNotFoundError('example-robot-data is not installed: '
                                "pip install '.[bench]'") from None
    return Path(dist.locate_file('cmeel.prefix/share/example-robot-data/robots'))
