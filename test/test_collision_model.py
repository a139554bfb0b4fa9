# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The arm's collision model (issue 29).

Its geometry from the URDF, the spheres that hold it, the pairs to skip, and where meshes may be
read from.
"""
from pathlib import Path

from ament_index_python.packages import get_package_share_directory
import numpy as np
import pytest
from trajplan_ros.collision.arm_geometry import ArmGeometry
from trajplan_ros.collision.distances import ArmCollision, CollisionWorld
from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.collision.scene import Scene
from trajplan_ros.collision.shapes import MeshSource
from trajplan_ros.collision.skip_pairs import read_srdf
from trajplan_ros.collision.spheres import SphereModel
from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.tools.bench.published_arms import PUBLISHED, robots_dir
import trimesh
import yourdfpy

PAPER_URDF = urdf_xml(paper_arm(), velocity=0.2)


def package_share(name: str) -> str:
    """Resolve package:// through the ament index, example-robot-data's (cmeel) prefix too."""
    if name == 'example-robot-data':
        return str(robots_dir().parents[0])
    return get_package_share_directory(name)


MESHES = MeshSource(package_share)


def published(name: str) -> tuple[ArmModel, Path]:
    arm = PUBLISHED[name]
    return ArmModel.from_urdf(arm.urdf, arm.base_link, arm.tip_link), arm.urdf


def geometry_of(name: str) -> ArmGeometry:
    if name == 'paper':
        return ArmGeometry.from_urdf(PAPER_URDF, paper_arm())
    arm, urdf = published(name)
    return ArmGeometry.from_urdf(urdf, arm, MESHES)


def surface_points(shape) -> np.ndarray:
    """Return the true shape's vertices (meshes) or dense surface samples (primitives)."""
    if shape.kind == 'mesh':
        points = shape.vertices
    elif shape.kind == 'box':
        points = trimesh.creation.box(extents=shape.dimensions).sample(2000, seed=0)
        points = np.vstack((points, trimesh.creation.box(extents=shape.dimensions).vertices))
    elif shape.kind == 'sphere':
        points = trimesh.creation.icosphere(4, radius=shape.dimensions[0]).vertices
    else:
        height, radius = shape.dimensions
        points = trimesh.creation.cylinder(radius=radius, height=height, sections=512).vertices
    return points @ shape.pose[:3, :3].T + shape.pose[:3, 3]


@pytest.mark.parametrize('name', ['paper', 'so101', 'ur5', 'panda'])
def test_the_spheres_hold_every_vertex_of_each_link(name: str) -> None:
    geometry = geometry_of(name)
    spheres = SphereModel.of(geometry)
    assert geometry.links
    for link_index, link in enumerate(geometry.links):
        span = slice(spheres.first[link_index], spheres.first[link_index + 1])
        centres, radii = spheres.centres[span], spheres.radii[span]
        for shape in link.shapes:
            points = surface_points(shape)
            gap = np.linalg.norm(points[:, None, :] - centres[None], axis=2) - radii
            assert np.all(gap.min(axis=1) <= 1e-9), (link.name, float(gap.min(axis=1).max()))


@pytest.mark.parametrize('name', ['ur5', 'panda'])
def test_link_poses_match_yourdfpy_and_sphere_bounds_never_exceed_coal(name: str) -> None:
    arm, urdf = published(name)
    srdf = next((robots_dir() / PUBLISHED[name].path).parents[1].glob('srdf/*.srdf'))
    if name == 'ur5':
        srdf = srdf.parent / 'ur5.srdf'
    model = ArmCollision.from_urdf(urdf, arm, meshes=MESHES, srdf=srdf.read_text())
    scene = Scene.from_dict({'obstacles': [
        {'id': 'table', 'type': 'box', 'dimensions': [1.2, 0.8, 0.04],
         'position': [0.3, 0.0, -0.05]},
        {'id': 'post', 'type': 'cylinder', 'dimensions': [0.8, 0.05], 'position': [0.4, 0.3, 0.4],
         'orientation': [0.0, 0.38268343, 0.0, 0.92387953]},
        {'id': 'ball', 'type': 'sphere', 'dimensions': [0.1], 'position': [-0.3, 0.2, 0.5]}]})
    world = CollisionWorld(model, scene)
    reference = yourdfpy.URDF.load(str(urdf), load_meshes=False, load_collision_meshes=False)
    q = np.random.default_rng(7).uniform(arm.lower, arm.upper, (25, arm.n_joints))
    every = np.arange(len(world.pairs))
    for row in q:
        poses = model.geometry.link_poses(row[None])[0]
        reference.update_cfg(dict(zip(arm.joint_names, row)))
        for i, link in enumerate(model.geometry.links):
            np.testing.assert_allclose(poses[i], reference.get_transform(link.name, arm.base_link),
                                       atol=1e-12)
        assert np.all(world.lower_bounds(poses, every) <= world.exact(poses, every) + 1e-9)


def test_an_srdf_names_the_pairs_and_a_bad_one_is_refused() -> None:
    srdf = ('<robot name="r"><disable_collisions link1="b" link2="a" reason="Adjacent"/>'
            '<disable_collisions link1="c" link2="d" reason="Never"/></robot>')
    assert read_srdf(srdf) == {('a', 'b'), ('c', 'd')}
    for bad, reason in (('<robot><disable_collisions link1="a"/></robot>', 'lacks link1 or link2'),
                        ('<robot>', 'not well-formed'),
                        ('<!DOCTYPE r [<!ENTITY e "x">]><robot/>', 'DTD'),
                        ('<srdf/>', 'not <robot>')):
        with pytest.raises(InvalidCollisionInput, match=reason):
            read_srdf(bad)


def test_the_computed_skip_pairs_are_moveit_s_reasons_and_repeat() -> None:
    arm = paper_arm()
    one = ArmCollision.from_urdf(PAPER_URDF, arm)
    two = ArmCollision.from_urdf(PAPER_URDF, arm)
    assert one.skip == two.skip
    assert one.skip_source.startswith('computed: ')
    # every link is adjacent to its parent; the base is never checked against the first link
    assert ('base_link', 'link1') in one.skip and ('link1', 'link2') in one.skip
    names = one.link_names
    checked = {tuple(sorted((names[a], names[b]))) for a, b in one.self_pairs}
    assert checked and not checked & one.skip
    assert ('base_link', 'link4') in checked               # far apart at the default pose


def test_meshes_are_read_only_from_packages_and_beside_the_file(tmp_path: Path) -> None:
    (tmp_path / 'inside').mkdir()
    trimesh.creation.box().export(tmp_path / 'inside' / 'box.stl')
    trimesh.creation.box().export(tmp_path / 'outside.stl')
    beside = MeshSource(folder=tmp_path / 'inside')
    vertices, faces = beside.load('box.stl', np.ones(3))
    assert len(faces) == 12 and np.ptp(vertices, axis=0).tolist() == [1.0, 1.0, 1.0]
    for uri, reason in (('../outside.stl', 'outside'), ('file:///etc/passwd', 'outside'),
                        ('http://example.com/a.stl', 'only package://'),
                        ('package://no_such_package_here/a.stl', 'not in the ament index'),
                        ('missing.stl', 'No such file')):
        with pytest.raises(InvalidCollisionInput, match=reason):
            MeshSource(get_package_share_directory, tmp_path / 'inside').load(uri, np.ones(3))
    with pytest.raises(InvalidCollisionInput, match='package://'):
        MeshSource().load('box.stl', np.ones(3))            # a URDF given as text


def test_meshes_over_the_limits_are_refused(tmp_path: Path,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    trimesh.creation.icosphere(3).export(tmp_path / 'ball.stl')
    from trajplan_ros.collision import shapes
    monkeypatch.setattr(shapes, 'MAX_MESH_BYTES', 1000)
    with pytest.raises(InvalidCollisionInput, match='byte limit'):
        MeshSource(folder=tmp_path).load('ball.stl', np.ones(3))
    monkeypatch.setattr(shapes, 'MAX_MESH_BYTES', 10**8)
    monkeypatch.setattr(shapes, 'MAX_MESH_VERTICES', 100)
    with pytest.raises(InvalidCollisionInput, match='vertices, over the limit'):
        MeshSource(folder=tmp_path).load('ball.stl', np.ones(3))
