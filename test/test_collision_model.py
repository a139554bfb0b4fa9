# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The arm's collision model.

Its geometry from the URDF, the spheres that hold it, the pairs to skip, where meshes may be
read from, and the convex sets (hulls, pieces, pair tables) that bound the distances below the
triangles'.
"""
from pathlib import Path

from ament_index_python.packages import get_package_share_directory
from mesh_arm import write_mesh_arm
import numpy as np
import pytest
from trajplan_ros.collision.arm_geometry import ArmGeometry
from trajplan_ros.collision.convex import pair_convex_bounds
from trajplan_ros.collision.distances import (ArmCollision, CollisionWorld, convex_hull,
                                              HULL_SLACK)
from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.collision.scene import Scene
from trajplan_ros.collision.shapes import MeshSource
from trajplan_ros.collision.skip_pairs import read_srdf
from trajplan_ros.collision.spheres import SphereModel
from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.tools.bench.cases import PUBLISHED, robots_dir
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


def two_link_urdf(first: str, second: str) -> str:
    """Return a URDF of two revolute joints whose links' meshes are ``first`` and ``second``."""
    def link(name: str, uri: str) -> str:
        return (f'<link name="{name}"><collision><geometry><mesh filename="{uri}"/></geometry>'
                '</collision></link>')
    joint = ('<joint name="{0}" type="revolute"><parent link="{1}"/><child link="{2}"/>'
             '<origin xyz="0 0 {3}"/><axis xyz="0 0 1"/>'
             '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>')
    return ('<robot name="pybullet_style"><link name="base"/>' + link('one', first)
            + link('two', second) + joint.format('j1', 'base', 'one', 0.1)
            + joint.format('j2', 'one', 'two', 0.3) + '</robot>')


def test_a_package_no_index_knows_is_read_beside_the_urdf_once_said(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    (tmp_path / 'meshes').mkdir()
    trimesh.creation.box(extents=(0.1, 0.1, 0.2)).export(tmp_path / 'meshes' / 'one.stl')
    trimesh.creation.icosphere(1, radius=0.05).export(tmp_path / 'two.obj')
    urdf = tmp_path / 'arm.urdf'
    # pybullet's layout (package://meshes/... is <folder>/meshes/...) and a package name that
    # is only a prefix to drop (<folder>/two.obj)
    urdf.write_text(two_link_urdf('package://meshes/one.stl', 'package://vendor_arm/two.obj'))
    arm = ArmModel.from_urdf(urdf, 'base', 'two')
    with caplog.at_level('WARNING', logger='trajplan_ros'):
        geometry = ArmGeometry.from_urdf(urdf, arm, MeshSource(get_package_share_directory,
                                                               tmp_path))
        ArmGeometry.from_urdf(urdf, arm)                       # no package lookup at all
    said = [r.getMessage() for r in caplog.records if 'beside the URDF' in r.getMessage()]
    assert len(said) == 2 and 'package://meshes/, package://vendor_arm/' in said[0]
    one, two = (link.shapes[0] for link in geometry.links)
    assert np.ptp(one.vertices, axis=0).tolist() == pytest.approx([0.1, 0.1, 0.2])
    assert np.max(np.linalg.norm(two.vertices, axis=1)) == pytest.approx(0.05)


def test_a_package_read_beside_the_urdf_may_not_leave_its_folder(tmp_path: Path) -> None:
    inside = tmp_path / 'robot'
    (inside / 'meshes').mkdir(parents=True)
    trimesh.creation.box().export(tmp_path / 'secret.stl')
    (inside / 'meshes' / 'link.stl').symlink_to(tmp_path / 'secret.stl')
    source = MeshSource(get_package_share_directory, inside)
    for uri, reason in (('package://meshes/link.stl', 'outside'),         # a link out
                        ('package://meshes/../../secret.stl', 'outside'),
                        ('package://../secret.stl', 'outside'),
                        ('package://meshes/absent.stl', 'not in the ament index, and neither')):
        with pytest.raises(InvalidCollisionInput, match=reason):
            source.load(uri, np.ones(3))
    with pytest.raises(InvalidCollisionInput, match='not in the ament index'):
        MeshSource(get_package_share_directory).load('package://meshes/x.stl', np.ones(3))


@pytest.fixture(scope='module')
def mesh_arm(tmp_path_factory: pytest.TempPathFactory) -> tuple[ArmModel, ArmCollision, Path]:
    """Return the concave-mesh arm of ``mesh_arm``: its model, collision model and URDF."""
    urdf = write_mesh_arm(tmp_path_factory.mktemp('mesh_arm'))
    arm = ArmModel.from_urdf(urdf, 'base_link', 'tip')
    return arm, ArmCollision.from_urdf(urdf, arm, samples=200), urdf


def test_hull_and_piece_bounds_never_exceed_the_triangles_and_decide_alike(mesh_arm) -> None:
    arm, model, _ = mesh_arm
    # a ball in the ring's hole: inside the ring's hull, clear of its triangles
    scene = Scene.from_dict({'obstacles': [
        {'id': 'in_hole', 'type': 'sphere', 'dimensions': [0.02], 'position': [0, 0, 0.07]},
        {'id': 'post', 'type': 'cylinder', 'dimensions': [0.4, 0.03],
         'position': [0.15, 0.1, 0.3]},
        {'id': 'crate', 'type': 'box', 'dimensions': [0.1, 0.1, 0.1],
         'position': [-0.2, 0.0, 0.45]}]})
    world = CollisionWorld(model, scene)
    every = np.arange(len(world.pairs))
    ring_hole = next(p for p in every if world.pair_name(p) == "ring with 'in_hole'")
    nothing = (np.empty((0, 4)), np.zeros(1, dtype=np.int64))
    for q in np.random.default_rng(5).uniform(-np.pi, np.pi, (40, arm.n_joints)):
        poses = model.geometry.link_poses(q[None])[0]
        exact = world.exact(poses, every)
        hulls = pair_convex_bounds(world.convexes.arrays, poses, world.pairs,
                                   np.full(len(every), np.inf), np.ones(len(every), bool),
                                   *nothing)
        assert np.all(hulls <= exact + 1e-12), float(np.max(hulls - exact))
        for needed in (0.0, 0.01, 0.03):
            bound, known = world.bounded(poses, every, np.full(len(every), needed))
            assert np.all(bound <= exact + 1e-12)
            np.testing.assert_array_equal(bound <= needed, exact <= needed)
            np.testing.assert_allclose(bound[known], exact[known], atol=1e-12)
            for p in every:
                assert world.within(poses, p, needed) == (exact[p] < needed), world.pair_name(p)
        # the ring's hull holds the ball, its triangles (and the hulls of their pieces) do not
        covers = pair_convex_bounds(world.convexes.arrays, poses, world.pairs,
                                    np.full(len(every), -np.inf), np.zeros(len(every), bool),
                                    *nothing)
        assert covers[ring_hole] < 0.0 < hulls[ring_hole] <= exact[ring_hole]


def test_convex_hulls_hold_their_points_even_flat_ones() -> None:
    rng = np.random.default_rng(3)
    flat = np.c_[rng.uniform(size=(40, 2)), np.zeros(40)]
    for points in (flat, flat[:, [0, 2, 1]], np.c_[rng.uniform(size=5), np.zeros((5, 2))],
                   np.eye(3), rng.normal(size=(200, 3)),
                   trimesh.creation.annulus(0.04, 0.06, 0.04).vertices):
        hull = convex_hull(points)
        normals = np.array([hull.normal(i) for i in range(hull.num_normals_and_offsets)])
        offsets = np.array([hull.offset(i) for i in range(hull.num_normals_and_offsets)])
        assert np.max(points @ normals.T + offsets) <= 1e-9
    assert convex_hull(np.ones((4, 3))) is None                  # one point: no solid


def test_a_detailed_mesh_lies_in_its_hull() -> None:
    vertices, faces = MESHES.load('package://example-robot-data/robots/so_arm_description/'
                                  'meshes/so101/moving_jaw_so101_v1.stl', np.ones(3))
    hull = convex_hull(vertices)
    normals = np.array([hull.normal(i) for i in range(hull.num_normals_and_offsets)])
    offsets = np.array([hull.offset(i) for i in range(hull.num_normals_and_offsets)])
    unique = np.unique(vertices, axis=0)
    assert max(float(np.max(chunk @ normals.T + offsets))
               for chunk in np.array_split(unique, 20)) <= HULL_SLACK


def test_a_pair_table_bounds_its_pair_over_every_turn(mesh_arm) -> None:
    arm, model, _ = mesh_arm
    (table,) = model.tables                        # the bar and the jaw: the last joint apart
    assert {model.link_names[i] for i in model.self_pairs[table.pair]} == {'bar', 'jaw'}
    world = CollisionWorld(model)
    for start, end in np.random.default_rng(8).uniform(-np.pi, np.pi, (30, 2)):
        q = np.zeros((25, arm.n_joints))
        q[:, table.joint] = np.linspace(start, end, 25)
        least = min(world.exact(poses, np.array([table.pair]))[0]
                    for poses in model.geometry.link_poses(q))
        assert table.least(start, end) <= least
