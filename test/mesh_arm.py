# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
A small arm of concave meshes, written into a folder: for the tests of the hull bounds.

Three revolute joints (about z, y, y) carry a ring (its hull fills the hole), a bar and a
U-shaped bracket; a jaw hangs from the bracket by a fixed joint, so the jaw and the bar are
moved against each other by the last joint alone (a pair table). The meshes are STL and OBJ
files beside the URDF, named as pybullet's files name them (``package://meshes/...``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

__all__ = ['write_mesh_arm']


def _bracket() -> trimesh.Trimesh:
    """Return a U of three boxes, open towards +x: concave, as a triangle soup."""
    def box(extents: tuple[float, float, float], centre: tuple[float, float, float]
            ) -> trimesh.Trimesh:
        return trimesh.creation.box(extents=extents,
                                    transform=trimesh.transformations.translation_matrix(centre))
    return trimesh.util.concatenate([box((0.01, 0.05, 0.25), (-0.02, 0.0, 0.125)),
                                     box((0.05, 0.05, 0.01), (0.0, 0.0, 0.005)),
                                     box((0.05, 0.05, 0.01), (0.0, 0.0, 0.245))])


def write_mesh_arm(folder: Path) -> Path:
    """Write the arm's URDF and meshes into ``folder``; return the URDF's path."""
    meshes = folder / 'meshes'
    meshes.mkdir(parents=True, exist_ok=True)
    trimesh.creation.annulus(r_min=0.04, r_max=0.06, height=0.04).export(meshes / 'ring.stl')
    trimesh.creation.box(extents=(0.04, 0.04, 0.3)).export(meshes / 'bar.stl')
    _bracket().export(meshes / 'bracket.obj')
    trimesh.creation.box(extents=(0.01, 0.02, 0.06)).export(meshes / 'jaw.stl')

    def link(name: str, mesh: str, xyz: tuple[float, ...]) -> str:
        return (f'<link name="{name}"><collision><origin xyz="{" ".join(map(str, xyz))}"/>'
                f'<geometry><mesh filename="package://meshes/{mesh}"/></geometry></collision>'
                '</link>')

    def joint(name: str, parent: str, child: str, xyz: tuple[float, ...], axis: str) -> str:
        kind = 'fixed' if axis == '' else 'revolute'
        limits = ('' if axis == '' else f'<axis xyz="{axis}"/>'
                  f'<limit lower="{-np.pi}" upper="{np.pi}" effort="1" velocity="1"/>')
        return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
                f'<child link="{child}"/><origin xyz="{" ".join(map(str, xyz))}"/>{limits}'
                '</joint>')

    urdf = folder / 'mesh_arm.urdf'
    urdf.write_text(
        '<robot name="mesh_arm"><link name="base_link"/>'
        + link('ring', 'ring.stl', (0, 0, 0.02)) + link('bar', 'bar.stl', (0, 0, 0.15))
        + link('bracket', 'bracket.obj', (0, 0, 0)) + link('jaw', 'jaw.stl', (0, 0, 0.03))
        + '<link name="tip"/>'
        + joint('j1', 'base_link', 'ring', (0, 0, 0.05), '0 0 1')
        + joint('j2', 'ring', 'bar', (0, 0, 0.1), '0 1 0')
        + joint('j3', 'bar', 'bracket', (0, 0, 0.3), '0 1 0')
        + joint('jaw_joint', 'bracket', 'jaw', (0.02, 0, 0.25), '')
        + joint('tip_joint', 'jaw', 'tip', (0, 0, 0.06), '') + '</robot>')
    return urdf
