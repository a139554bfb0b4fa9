# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The URDF puts every frame where the DH model does, with the model's joint values and limits."""
from __future__ import annotations

from pathlib import Path
import xml.etree.ElementTree as ET

from node_under_test import Install
import numpy as np
import pytest

from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.search.objective import DEFAULT_OMEGA
from trajplan_ros.tools.cli import main

RESOURCE = Path(__file__).resolve().parents[1] / 'resource' / 'paper_arm.urdf'


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Return the rotation by Rodrigues' formula (written here, independently of the module)."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    skew = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * skew + (1 - np.cos(angle)) * skew @ skew


def _origin(joint: ET.Element) -> np.ndarray:
    origin = joint.find('origin')
    xyz = np.array(origin.get('xyz').split(), dtype=float)
    roll, pitch, yaw = np.array(origin.get('rpy').split(), dtype=float)
    t = np.eye(4)
    t[:3, :3] = (_rotation([0, 0, 1], yaw) @ _rotation([0, 1, 0], pitch)
                 @ _rotation([1, 0, 0], roll))                     # URDF: fixed-axis X, Y, Z
    t[:3, 3] = xyz
    return t


def _chain(root: ET.Element) -> list[ET.Element]:
    """Return the joints from base_link to tool_link, in order, following parent/child links."""
    by_parent = {j.find('parent').get('link'): j for j in root.iter('joint')}
    joints, link = [], 'base_link'
    while link != 'tool_link':
        joint = by_parent[link]
        joints.append(joint)
        link = joint.find('child').get('link')
    return joints


def _urdf_frames(root: ET.Element, q: np.ndarray) -> list[np.ndarray]:
    """Return the world transform of every child link along the chain for joint values q."""
    out, t, k = [], np.eye(4), 0
    for joint in _chain(root):
        t = t @ _origin(joint)
        if joint.get('type') == 'revolute':
            turn = np.eye(4)
            axis = np.array(joint.find('axis').get('xyz').split(), dtype=float)
            turn[:3, :3] = _rotation(axis, q[k])
            t = t @ turn
            k += 1
        out.append(t)
    return out


def _random_arm(rng: np.random.Generator, n: int) -> ArmModel:
    quarter = np.pi / 2
    return ArmModel.from_dh(
        a=rng.uniform(0, 0.2, n), alpha=rng.choice([-quarter, 0, quarter, 0.3], n),
        d=rng.uniform(0, 0.2, n) * (rng.random(n) < 0.5), sign=rng.choice([-1, 1], n),
        offset=rng.choice([-quarter, 0, quarter, np.pi, 0.7], n),
        lower=-rng.uniform(1, 3, n), upper=rng.uniform(1, 3, n), planned=min(n, 4))


@pytest.mark.parametrize('arm', [paper_arm(), _random_arm(np.random.default_rng(3), 6),
                                 _random_arm(np.random.default_rng(4), 3)],
                         ids=['paper', 'random6', 'random3'])
def test_urdf_chain_matches_dh_kinematics(arm: ArmModel) -> None:
    root = ET.fromstring(urdf_xml(arm, velocity=DEFAULT_OMEGA))
    rng = np.random.default_rng(0)
    for q in arm.lower + (arm.upper - arm.lower) * rng.random((50, arm.n_joints)):
        urdf = _urdf_frames(root, q)
        dh = arm.frames(q)[0]
        pos, axis = arm.tool(q[None, :])
        assert np.allclose(urdf[-1][:3, 3], pos[0], rtol=0, atol=1e-9)
        assert np.allclose(urdf[-1][:3, 2], axis[0], rtol=0, atol=1e-9)
        assert np.allclose(urdf[-1], dh[-1], rtol=0, atol=1e-9)          # whole tool frame
        for k in range(arm.n_joints):                                      # every joint's position
            assert np.allclose(urdf[k][:3, 3], dh[k][:3, 3], rtol=0, atol=1e-9)


def test_urdf_joints_carry_model_names_and_limits() -> None:
    arm = paper_arm()
    root = ET.fromstring(urdf_xml(arm, velocity=DEFAULT_OMEGA))
    revolute = [j for j in _chain(root) if j.get('type') == 'revolute']
    assert [j.get('name') for j in revolute] == list(arm.joint_names)
    for j, lo, hi in zip(revolute, arm.lower, arm.upper):
        limit = j.find('limit')
        assert float(limit.get('lower')) == pytest.approx(lo, abs=1e-15)
        assert float(limit.get('upper')) == pytest.approx(hi, abs=1e-15)
        assert float(limit.get('velocity')) > 0 and float(limit.get('effort')) > 0
    links = {link.get('name') for link in root.iter('link')}
    assert {'base_link', 'tool_link'} <= links
    assert all(link.find('visual/geometry') is not None for link in root.iter('link'))
    # q = 0 is the upright pose with the tool at the paper's initial position (37, 0, 337) mm
    assert np.allclose(_urdf_frames(root, np.zeros(5))[-1][:3, 3], [0.037, 0, 0.337], atol=1e-12)


def test_installed_resource_is_current() -> None:
    assert RESOURCE.read_text(encoding='utf-8') == urdf_xml(paper_arm(), velocity=DEFAULT_OMEGA)


@pytest.mark.system
def test_urdf_is_installed_with_the_package(colcon_install: Install) -> None:
    """Check setup.py installs resource/*.urdf to share/trajplan_ros/urdf/ (colcon build)."""
    installed = colcon_install.prefix / 'share' / 'trajplan_ros' / 'urdf' / 'paper_arm.urdf'
    assert installed.read_text(encoding='utf-8') == RESOURCE.read_text(encoding='utf-8')


def test_cli_prints_and_writes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(['urdf']) == 0
    assert capsys.readouterr().out == urdf_xml(paper_arm(), velocity=DEFAULT_OMEGA)
    out = tmp_path / 'arm.urdf'
    assert main(['urdf', '-o', str(out), '--name', 'my_arm']) == 0
    assert ET.parse(out).getroot().get('name') == 'my_arm'
