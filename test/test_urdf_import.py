# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Chains from URDF: published vendor arms, the paper arm's own URDF, refusals, untrusted text."""
from __future__ import annotations

from pathlib import Path
import time

from hostile_urdf import BILLION_LAUGHS
import numpy as np
import pytest

from trajplan_ros.kinematics import ArmModel, InvalidArmModel, paper_arm
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.planning import plan
from trajplan_ros.search.objective import DEFAULT_OMEGA
from trajplan_ros.tools.bench.cases import PUBLISHED
import yourdfpy


def published(name: str, **kwargs) -> ArmModel:
    arm = PUBLISHED[name]
    return ArmModel.from_urdf(arm.urdf, arm.base_link, arm.tip_link, **kwargs)


def _samples(arm: ArmModel, rng: np.random.Generator, n: int) -> np.ndarray:
    lo = np.where(np.isfinite(arm.lower), arm.lower, -np.pi)
    hi = np.where(np.isfinite(arm.upper), arm.upper, np.pi)
    return rng.uniform(lo, hi, (n, arm.n_joints))


@pytest.mark.parametrize('name', sorted(PUBLISHED))
def test_fk_agrees_with_yourdfpy_on_published_arms(name: str) -> None:
    base, tip = PUBLISHED[name].base_link, PUBLISHED[name].tip_link
    arm = published(name, tool_offset=(0.01, -0.02, 0.03))
    assert arm.n_joints == arm.planned == PUBLISHED[name].joints
    other = yourdfpy.URDF.load(str(PUBLISHED[name].urdf), build_scene_graph=True,
                               load_meshes=False, load_collision_meshes=False)
    rng = np.random.default_rng(7)
    q = _samples(arm, rng, 40)
    p, u = arm.tool(q)
    frames = arm.frames(q)
    for k in range(len(q)):
        other.update_cfg(dict(zip(arm.joint_names, q[k])))
        tip_frame = other.get_transform(frame_to=tip, frame_from=base)
        assert np.allclose(p[k], tip_frame[:3, :3] @ (0.01, -0.02, 0.03) + tip_frame[:3, 3],
                           rtol=0, atol=1e-9)
        assert np.allclose(u[k], tip_frame[:3, 2], rtol=0, atol=1e-9)
        assert np.allclose(frames[k, -1, :3, :3], tip_frame[:3, :3], rtol=0, atol=1e-9)
    # the reach bound of eq. (14) holds about the first joint
    far = np.linalg.norm(arm.tool(_samples(arm, rng, 2000))[0] - arm.reach_centre, axis=1)
    assert far.max() <= arm.reach


def test_jacobian_is_the_derivative_on_a_urdf_chain() -> None:
    arm = published('ur5', tool_offset=(0.0, 0.05, 0.1), tool_axis=(1.0, 0.0, 0.0))
    q = _samples(arm, np.random.default_rng(2), 5)
    jac = arm.tool_jacobian(q)
    h = 1e-6
    for i in range(arm.n_joints):
        step = np.zeros(arm.n_joints)
        step[i] = h
        (p1, u1), (p0, u0) = arm.tool(q + step), arm.tool(q - step)
        assert np.allclose(jac.jp[:, :, i], (p1 - p0) / (2 * h), atol=1e-8)
        assert np.allclose(jac.ju[:, :, i], (u1 - u0) / (2 * h), atol=1e-8)


def test_the_paper_arms_urdf_gives_the_dh_model() -> None:
    dh = paper_arm()
    arm = ArmModel.from_urdf(urdf_xml(dh, velocity=DEFAULT_OMEGA), 'base_link', 'tool_link')
    assert arm.joint_names == dh.joint_names and arm.n_joints == 5
    q = _samples(dh, np.random.default_rng(1), 200)
    for a, b in zip(arm.tool(q), dh.tool(q)):
        assert np.allclose(a, b, rtol=0, atol=1e-12)
    assert np.allclose(arm.frames(q)[:, -1], dh.frames(q)[:, -1], rtol=0, atol=1e-12)
    assert arm.reach >= dh.reach - 1e-12


def test_planning_from_the_paper_arms_urdf_gives_the_same_answers() -> None:
    dh = paper_arm()
    arm = ArmModel.from_urdf(urdf_xml(dh, velocity=DEFAULT_OMEGA), 'base_link', 'tool_link')
    rng = np.random.default_rng(5)
    for k in range(4):
        goal = dh.tool(_samples(dh, rng, 1))[0][0]
        # the URDF plans all five joints; the DH model its four (joint 5 spins the tool in place)
        a = plan(goal, arm=arm, seed=k)
        b = plan(goal, arm=dh, seed=k)
        assert a.success and b.success
        assert a.motion_time_s == pytest.approx(b.motion_time_s, rel=1e-6)
        assert np.allclose(a.joint_goal[:4], b.joint_goal[:4], atol=1e-5)


def test_automatic_base_and_tip() -> None:
    arm = ArmModel.from_urdf(PUBLISHED['ur5'].urdf)        # root: world
    assert (arm.base_link, arm.tip_link) == ('world', 'wrist_3_link')
    # the Panda's fingers are prismatic, on side branches: the revolute chain ends at link 7
    panda = ArmModel.from_urdf(PUBLISHED['panda'].urdf)
    assert panda.tip_link == 'panda_link7' and panda.n_joints == 7


def test_continuous_joints_have_no_limits_and_the_nearest_goal_angle() -> None:
    arm = published('kinova')
    assert arm.continuous.tolist() == [True, False, False, True, False, True]
    rng = np.random.default_rng(3)
    q = _samples(arm, rng, 1)[0]
    start = q.copy()
    start[arm.continuous] += 2.6                # far from the goal's own angles
    result = plan(arm.tool(q[None])[0][0], arm=arm, start=start, seed=0)
    assert result.success
    assert np.all(np.abs(result.joint_goal - start)[arm.continuous] <= np.pi + 1e-9)


def test_each_joint_turns_at_most_at_its_velocity_limit() -> None:
    dh = paper_arm()
    a, alpha, d = dh.dh
    slow = ArmModel.from_dh(a, alpha, d, sign=dh.sign, offset=dh.offset, lower=dh.lower,
                            upper=dh.upper, velocity=[0.05, 1, 1, 1, 1], planned=4)
    result = plan((0.15, 0.19, 0.17), arm=slow, seed=0)
    assert result.success
    speeds = np.array([0.05, 0.2, 0.2, 0.2, 0.2])
    moved = np.abs(result.joint_goal - result.start)
    assert result.motion_time_s == pytest.approx(np.max(moved / speeds), rel=1e-12)
    traj = result.trajectory(slow)
    moved = np.diff(np.vstack((traj.start, traj.positions)), axis=0)
    velocity = moved / np.diff(traj.times, prepend=0.0)[:, None]
    assert np.all(np.abs(velocity) <= speeds * (1 + 1e-9))
    assert traj.duration == pytest.approx(result.motion_time_s)


def _chain_urdf(joints: list[tuple[str, str]], extra: str = '') -> str:
    """Return a URDF of links l0..ln joined by joints (name, type), each 0.1 m along z."""
    links = ''.join(f'<link name="l{i}"/>' for i in range(len(joints) + 1))
    body = ''.join(
        f'<joint name="{name}" type="{kind}"><parent link="l{i}"/><child link="l{i + 1}"/>'
        '<origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 1 0"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        for i, (name, kind) in enumerate(joints))
    return f'<?xml version="1.0"?><robot name="r">{links}{body}{extra}</robot>'


def _first_joint(old: str, new: str) -> str:
    """Return a two-joint chain with ``old`` replaced by ``new`` in its first joint."""
    return _chain_urdf([('a', 'revolute'), ('b', 'revolute')]).replace(old, new, 1)


@pytest.mark.parametrize('text, base, tip, reason', [
    (_chain_urdf([('a', 'revolute'), ('b', 'prismatic'), ('c', 'revolute')]), None, None,
     r"joint 'b' on the chain is prismatic"),
    (_chain_urdf([('a', 'revolute'), ('b', 'revolute')]).replace(
        '<axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        '</robot>', '<axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/>'
        '<mimic joint="a"/></joint></robot>'), None, None, r"mimics 'a'"),
    (_chain_urdf([('a', 'revolute'), ('b', 'fixed')]), None, None, r'has 1 revolute joints'),
    (_chain_urdf([(f'j{i}', 'revolute') for i in range(8)]), None, None, r'has 8 revolute'),
    (_chain_urdf([('a', 'revolute'), ('b', 'revolute')]), 'l0', 'nowhere', r'unknown link'),
    (_chain_urdf([('a', 'revolute'), ('b', 'revolute')]), 'l2', 'l0', r'not below link'),
    (_chain_urdf([('a', 'revolute'), ('b', 'revolute')], '<link name="x"/><joint name="s" '
                 'type="revolute"><parent link="l0"/><child link="x"/><axis xyz="0 0 1"/>'
                 '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'),
     None, None, r'ambiguous: .* end at l2, x'),
    ('<robot name="r"><link name="a"/>', None, None, r'not well-formed XML'),
    (_chain_urdf([('a', 'revolute'), ('b', 'revolute')], '<joint name="back" type="fixed">'
                 '<parent link="l2"/><child link="l0"/></joint>'), None, 'l2', r'cycle'),
    (_chain_urdf([('a', 'revolute'), ('b', 'revolute')], '<link name="x"/><joint name="self" '
                 'type="fixed"><parent link="x"/><child link="x"/></joint>'), 'l0', 'l2',
     r'cycle'),
    (_first_joint('<axis xyz="0 1 0"/>', '<axis xyz="1 0"/>'), None, None,
     r"joint 'a' has no usable axis"),
    (_first_joint('<axis xyz="0 1 0"/>', '<axis xyz="0 0 1 5"/>'), None, None,
     r"joint 'a' has no usable axis"),
    (_first_joint('velocity="1"', 'velocity="1e-320"'), None, None, r'too slow to plan with'),
    (_first_joint('xyz="0 0 0.1"', 'xyz="0 0 1e308"'), None, None, r'unusable origin'),
    ('<robot><link name="a"/></robot>', None, None, r'not <robot name='),
    ('/no/such/file.urdf', None, None, r'cannot read the URDF'),
])
def test_bad_chains_are_refused_with_a_reason(text, base, tip, reason) -> None:
    began = time.monotonic()
    with pytest.raises(InvalidArmModel, match=reason):
        ArmModel.from_urdf(text, base, tip)
    assert time.monotonic() - began < 1.0                      # a cycle does not hang it


def test_a_huge_tool_offset_is_refused() -> None:
    so101 = PUBLISHED['so101']
    with pytest.raises(InvalidArmModel, match='not an arm'):
        ArmModel.from_urdf(so101.urdf, so101.base_link, so101.tip_link,
                           tool_offset=(1e308, 1e308, 0.0))


def test_a_gripper_jaw_is_not_taken_for_the_tip() -> None:
    # the SO-101's last revolute joint moves the jaw, a leaf beside gripper_frame_link
    so101 = PUBLISHED['so101']
    with pytest.raises(InvalidArmModel, match=r'the tip link is ambiguous: the last revolute '
                       r"joint 'gripper' moves the leaf link 'moving_jaw_so101_v1_link' .*one "
                       r"of 'moving_jaw_so101_v1_link', 'gripper_frame_link'$"):
        ArmModel.from_urdf(so101.urdf)
    assert ArmModel.from_urdf(so101.urdf, tip_link='gripper_frame_link').n_joints == 5
    assert ArmModel.from_urdf(so101.urdf, tip_link='moving_jaw_so101_v1_link').n_joints == 6
    # a chain whose last joint's child is a leaf with no sibling keeps today's rule
    joints = [('j1', 'revolute'), ('j2', 'revolute')]
    assert ArmModel.from_urdf(_chain_urdf(joints)).n_joints == 2
    frame = ('<link name="frame"/><joint name="f" type="fixed"><parent link="l1"/>'
             '<child link="frame"/></joint>')
    with pytest.raises(InvalidArmModel, match=r"one of 'l2', 'frame'$"):
        ArmModel.from_urdf(_chain_urdf(joints, frame))


def test_an_unknown_link_is_refused_with_the_links_names() -> None:
    so101 = PUBLISHED['so101']
    with pytest.raises(InvalidArmModel, match=r"unknown link 'nosuch'; the URDF has 8 links: "
                                              r'base_link, shoulder_link, .*, gripper_frame_link'):
        ArmModel.from_urdf(so101.urdf, tip_link='nosuch')
    many = _chain_urdf([(f'j{i}', 'fixed') for i in range(30)])
    with pytest.raises(InvalidArmModel, match=r'has 31 links: l0, l1, .*, l19 and 11 more$'):
        ArmModel.from_urdf(many, tip_link='nosuch')


def test_untrusted_text_is_refused_quickly_without_reading_files(tmp_path: Path) -> None:
    secret = tmp_path / 'secret.txt'
    secret.write_text('do not read')
    external = ('<?xml version="1.0"?><!DOCTYPE r [<!ENTITY x SYSTEM "file://' + str(secret)
                + '">]><robot name="r"><link name="&x;"/></robot>')
    big = _chain_urdf([('a', 'revolute'), ('b', 'revolute')]).replace(
        '</robot>', '<!--' + 'x' * (10 * 1024 * 1024) + '--></robot>')
    many = _chain_urdf([('a', 'revolute'), ('b', 'revolute')]).replace(
        '</robot>', ''.join(f'<link name="extra{i}"/>' for i in range(1000)) + '</robot>')
    for text, reason in ((BILLION_LAUGHS, 'DTD'), (external, 'DTD'),
                         (big, 'over the 10485760 byte limit'), (many, 'over the limit of 1000')):
        began = time.monotonic()
        with pytest.raises(InvalidArmModel, match=reason):
            ArmModel.from_urdf(text)
        assert time.monotonic() - began < 1.0


def test_a_wrist_roll_plans_only_when_it_can_move_the_tool() -> None:
    chain = ArmModel.from_urdf(urdf_xml(paper_arm(), velocity=DEFAULT_OMEGA), 'base_link',
                               'tool_link')
    assert chain.planned == 5
    # the paper arm's joint 5 turns the tool about its own axis: held in both modes
    assert chain.without_idle_tail(axis=False).planned == 4
    assert chain.without_idle_tail(axis=True).planned == 4
    offset = ArmModel.from_urdf(urdf_xml(paper_arm(), velocity=DEFAULT_OMEGA), 'base_link',
                                'tool_link', tool_offset=(0.02, 0.0, 0.0))
    assert offset.without_idle_tail(axis=False) is offset
    sideways = ArmModel.from_urdf(urdf_xml(paper_arm(), velocity=DEFAULT_OMEGA), 'base_link',
                                  'tool_link', tool_axis=(1.0, 0.0, 0.0))
    assert sideways.without_idle_tail(axis=False).planned == 4
    assert sideways.without_idle_tail(axis=True) is sideways


def test_a_roll_off_the_tool_axis_by_rounding_is_held() -> None:
    # the UR5's tool0 axis misses its wrist_3 axis by 5e-12 rad (rounded rpy in the file)
    ur5 = PUBLISHED['ur5']
    arm = ArmModel.from_urdf(ur5.urdf, ur5.base_link, ur5.tip_link)
    assert arm.without_idle_tail(axis=False).planned == 5
    assert arm.without_idle_tail(axis=True).planned == 5


def test_vendor_extras_parse_without_reading_meshes() -> None:
    so101 = PUBLISHED['so101']
    text = so101.urdf.read_text(encoding='utf-8')
    # the old transmission syntax (type as an attribute), the new one, gazebo tags; the
    # published files already hold package:// meshes that do not exist here
    extras = (
        '<transmission name="old" type="pr2_mechanism_model/SimpleTransmission">'
        '<joint name="shoulder_pan"/><actuator name="m1"/>'
        '<mechanicalReduction>1</mechanicalReduction></transmission>'
        '<transmission name="new"><type>transmission_interface/SimpleTransmission</type>'
        '<joint name="elbow_flex"><hardwareInterface>hardware_interface/PositionJointInterface'
        '</hardwareInterface></joint><actuator name="m2"><mechanicalReduction>1'
        '</mechanicalReduction></actuator></transmission>'
        '<gazebo reference="base_link"><material>Gazebo/Grey</material></gazebo>'
        '<link name="world"/><joint name="world_joint" type="fixed"><parent link="world"/>'
        '<child link="base_link"/></joint>')
    assert 'package://' in text
    arm = ArmModel.from_urdf(text.replace('</robot>', extras + '</robot>'),
                             tip_link=so101.tip_link)
    assert arm.base_link == 'world' and arm.n_joints == 5
    plain = published('so101')
    q = _samples(arm, np.random.default_rng(0), 5)
    assert np.allclose(arm.tool(q)[0], plain.tool(q)[0], atol=1e-12)
