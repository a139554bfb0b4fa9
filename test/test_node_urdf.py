# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The planner node with a real arm's URDF, over real DDS.

The SO-101's published URDF arrives on ``robot_description`` the way robot_state_publisher
offers it (reliable, transient local); the node then plans its five joints by their URDF names.
A bad description is refused and the arm in use is kept; goals also come from RViz's
``clicked_point``.
"""
from __future__ import annotations

from typing import Any, Iterator

from geometry_msgs.msg import PointStamped, PoseStamped
from hostile_urdf import BILLION_LAUGHS
from nav_msgs.srv import GetPlan
from node_under_test import (check_servo_trajectory, fmt, NodeProcess, started_from,
                             trajectory_to)
import numpy as np
import pytest
from rclpy.duration import Duration
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory
from trajplan_ros import ArmModel
from trajplan_ros.kinematics.rotations import quaternions
from trajplan_ros.tools.bench.cases import PUBLISHED
from trajplan_ros.tools.ros_client import plan_request, RosClient
import yourdfpy

pytestmark = pytest.mark.dds


NS = '/so101_ns'
SO101 = PUBLISHED['so101']
ARM = ArmModel.from_urdf(SO101.urdf, SO101.base_link, SO101.tip_link)
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)


@pytest.fixture(scope='module')
def planner(start_node) -> Iterator[NodeProcess]:
    node = start_node('-r', f'__ns:={NS}', '-p', f'base_link:={SO101.base_link}',
                      '-p', f'tip_link:={SO101.tip_link}')
    yield node
    assert node.stop() == 0, node.output


@pytest.fixture(scope='module')
def describe(planner: NodeProcess, peer: RosClient):
    """Give a function that publishes a robot_description as robot_state_publisher does."""
    pub = peer.node.create_publisher(String, f'{NS}/robot_description', LATCHED)

    def publish(text: str) -> None:
        pub.publish(String(data=text))
        assert pub.wait_for_all_acked(Duration(seconds=30))

    return publish


@pytest.fixture(scope='module')
def trajectories(planner: NodeProcess, peer: RosClient):
    return peer.inbox(JointTrajectory, f'{NS}/joint_trajectory')


def _goal(seed: int) -> tuple[float, float, float]:
    q = np.random.default_rng(seed).uniform(ARM.lower, ARM.upper)
    return tuple(ARM.tool(q[None])[0][0].round(4).tolist())


def _tip(q: np.ndarray) -> np.ndarray:
    """Return the tip position by yourdfpy's FK (not ours)."""
    other = yourdfpy.URDF.load(str(SO101.urdf), build_scene_graph=True, load_meshes=False,
                               load_collision_meshes=False)
    other.update_cfg(dict(zip(ARM.joint_names, q)))
    return other.get_transform(frame_to=SO101.tip_link, frame_from=SO101.base_link)[:3, 3]


def test_a_described_arm_plans_by_its_urdf_names(planner, describe, peer, trajectories) -> None:
    mark = planner.mark()
    describe(SO101.urdf.read_text(encoding='utf-8'))
    planner.wait_for(r'arm for the next plan: 5-joint arm \(shoulder_pan, shoulder_lift, '
                     r'elbow_flex, wrist_flex, wrist_roll\) from robot_description, chain '
                     r'base_link -> gripper_frame_link', mark)
    goal = _goal(1)
    answer = peer.call(GetPlan, f'{NS}/plan_trajectory', plan_request(goal))
    assert answer.plan.poses and answer.plan.header.frame_id == 'base_link'
    _, start = started_from(planner, 'service call', goal, mark)
    msg = trajectory_to(trajectories, goal, arm=ARM)
    end = check_servo_trajectory(msg, start, names=ARM.joint_names)
    assert np.linalg.norm(_tip(end) - goal) <= 1e-6


def test_a_bad_description_is_refused_and_the_arm_kept(planner, describe, peer,
                                                       trajectories) -> None:
    describe(SO101.urdf.read_text(encoding='utf-8'))
    for text, reason in ((BILLION_LAUGHS, 'declares a DTD'),
                         ('<robot name="r"><link name="a"/></robot>', 'unknown link .base_link.'),
                         ('<robot name="r"><link', 'not well-formed XML')):
        mark = planner.mark()
        describe(text)
        planner.wait_for(rf'robot_description refused: .*{reason}.*; keeping 5-joint arm '
                         r'\(shoulder_pan', mark)
    goal = _goal(2)
    answer = peer.call(GetPlan, f'{NS}/plan_trajectory', plan_request(goal))
    assert answer.plan.poses
    assert tuple(trajectory_to(trajectories, goal, arm=ARM).joint_names) == ARM.joint_names


def test_clicked_points_in_a_frame_of_the_robot_are_goals(
        planner, describe, peer, trajectories) -> None:
    describe(SO101.urdf.read_text(encoding='utf-8'))
    goal = _goal(3)
    mark = planner.mark()
    elsewhere = PointStamped()
    elsewhere.header.frame_id = 'world'
    elsewhere.point.x, elsewhere.point.y, elsewhere.point.z = goal
    peer.publish(PointStamped, f'{NS}/clicked_point', elsewhere)
    planner.wait_for(rf"clicked_point #\d+ {fmt(goal)} m: refused: frame 'world' is not a link "
                     r'of the robot; known frames: base_link, gripper_frame_link', mark)
    clicked = PointStamped()
    clicked.header.frame_id = 'base_link'
    clicked.point = elsewhere.point
    peer.publish(PointStamped, f'{NS}/clicked_point', clicked)
    planner.wait_for(rf'clicked_point #\d+ {fmt(goal)} m from q = .*: reached', mark)
    trajectory_to(trajectories, goal, arm=ARM)


def test_a_goal_pose_in_a_root_frame_above_the_base_is_planned_in_the_base(
        planner, describe, peer, trajectories) -> None:
    """As the SO-ARM packages describe it: a world link above base_link, 0.1 m off."""
    text = SO101.urdf.read_text(encoding='utf-8')
    world = ('<link name="world"/><joint name="world_to_base" type="fixed"><parent link="world"/>'
             '<child link="base_link"/><origin xyz="0.1 0 0.05" rpy="0 0 0"/></joint>')
    describe(text.replace('<link name="base_link"', world + '<link name="base_link"', 1))
    goal = _goal(4)
    mark = planner.mark()
    pose = PoseStamped()
    pose.header.frame_id = 'world'
    pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = (
        goal[0] + 0.1, goal[1], goal[2] + 0.05)
    peer.publish(PoseStamped, f'{NS}/goal_pose', pose)
    planner.wait_for(rf"goal_pose #\d+ {fmt(goal)} m \(in 'world': .*\) from q = .*: reached",
                     mark)
    trajectory_to(trajectories, goal, arm=ARM)
    pose.header.frame_id = 'camera_link'
    peer.publish(PoseStamped, f'{NS}/goal_pose', pose)
    planner.wait_for(r"goal_pose #\d+ .* refused: frame 'camera_link' is not a link of the "
                     r'robot; known frames: base_link, .*world', mark)


def test_a_goal_pose_orientation_is_the_approach_direction(planner, describe, peer) -> None:
    describe(SO101.urdf.read_text(encoding='utf-8'))
    results = peer.set_parameters(f'{NS}/trajplan', [
        Parameter('goal_orientation', value='approach')])
    assert results[0].successful, results[0].reason
    mark = planner.mark()
    pose = PoseStamped()
    pose.header.frame_id = 'base_link'
    pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = 0.2, 0.1, 0.02
    pose.pose.orientation.x, pose.pose.orientation.w = 1.0, 0.0     # z axis down: from above
    peer.publish(PoseStamped, f'{NS}/goal_pose', pose)
    line = planner.wait_for(r'goal_pose #\d+ \(0.2, 0.1, 0.02\) m from q = .*: reached in .*, '
                            r'axis (\S+) rad from the approach direction', mark)
    assert float(line.group(1)) <= 1e-3
    pose.pose.orientation.x, pose.pose.orientation.w = 0.0, 1.0     # z axis up: not from above
    peer.publish(PoseStamped, f'{NS}/goal_pose', pose)
    planner.wait_for(r'goal_pose #\d+ \(0.2, 0.1, 0.02\) m from q = .*: not_reached: .*, axis '
                     r'\S+ rad from the approach direction', mark)
    results = peer.set_parameters(f'{NS}/trajplan', [Parameter('goal_orientation',
                                                               value='ignore')])
    assert results[0].successful


def test_a_goal_pose_is_planned_as_a_whole_pose(planner, describe, peer) -> None:
    # a tool frame of the five-joint arm at a configuration: reachable with its orientation;
    # the same point with the tool turned about its axis by 0.5 rad is not
    describe(SO101.urdf.read_text(encoding='utf-8'))
    results = peer.set_parameters(f'{NS}/trajplan', [Parameter('goal_orientation', value='pose')])
    assert results[0].successful, results[0].reason
    frame = ARM.frames(np.array([[0.239, -1.222, -0.228, 0.561, -0.383]]))[0, -1]
    turned = frame[:3, :3] @ [[np.cos(0.5), -np.sin(0.5), 0.0], [np.sin(0.5), np.cos(0.5), 0.0],
                              [0.0, 0.0, 1.0]]
    mark = planner.mark()
    for rotation, outcome in ((frame[:3, :3], 'reached in'), (turned, 'not_reached: ')):
        pose = PoseStamped()
        pose.header.frame_id = 'base_link'
        pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = frame[:3, 3]
        o = pose.pose.orientation
        o.x, o.y, o.z, o.w = (float(v) for v in quaternions(rotation[None])[0])
        peer.publish(PoseStamped, f'{NS}/goal_pose', pose)
        line = planner.wait_for(rf'goal_pose #\d+ {fmt(frame[:3, 3])} m from q = .*: {outcome}'
                                r'.*orientation (?:is )?(\S+) rad from the goal orientation',
                                mark)
        assert float(line.group(1)) <= 1e-6 or outcome != 'reached in'
    results = peer.set_parameters(f'{NS}/trajplan', [Parameter('goal_orientation',
                                                               value='ignore')])
    assert results[0].successful


def test_compute_plan_answers_and_publishes_nothing(
        planner, describe, peer, trajectories) -> None:
    describe(SO101.urdf.read_text(encoding='utf-8'))
    looked, moved = _goal(5), _goal(6)
    mark = planner.mark()
    answer = peer.call(GetPlan, f'{NS}/compute_plan', plan_request(looked))
    assert answer.plan.poses                                  # the plan, to look at
    planner.wait_for(rf'compute_plan call #\d+ {fmt(looked)} m .* answered, not sent', mark)
    assert peer.call(GetPlan, f'{NS}/plan_trajectory', plan_request(moved)).plan.poses
    ends = []                           # every trajectory published up to the second goal's
    while not ends or np.linalg.norm(ends[-1] - moved) > 1e-5:
        msg = trajectories.get(timeout=30.0)
        ends.append(ARM.tool(np.array(msg.points[-1].positions)[None])[0][0])
    assert all(np.linalg.norm(end - looked) > 1e-5 for end in ends)


def test_a_moveit_joint_limits_file_with_the_gripper_is_taken_with_a_warning(
        planner, describe, peer, tmp_path) -> None:
    describe(SO101.urdf.read_text(encoding='utf-8'))
    limits = tmp_path / 'joint_limits.yaml'
    limits.write_text('default_velocity_scaling_factor: 0.1\n'
                      'default_acceleration_scaling_factor: 0.5\njoint_limits:\n' + ''.join(
                          f'  {name}:\n    has_velocity_limits: true\n    max_velocity: 10\n'
                          '    has_acceleration_limits: true\n    max_acceleration: 10\n'
                          '    has_jerk_limits: false\n'
                          for name in (*ARM.joint_names, 'gripper')), encoding='utf-8')
    mark = planner.mark()
    results = peer.set_parameters(f'{NS}/trajplan', [
        Parameter('joint_limits_file', value=str(limits))])
    assert results[0].successful, results[0].reason
    planner.wait_for(r'joint_limits_file: joints gripper are not in the planned chain', mark)
    results = peer.set_parameters(f'{NS}/trajplan', [Parameter('joint_limits_file', value='')])
    assert results[0].successful


def test_start_positions_must_match_the_chain(planner, describe, peer: RosClient) -> None:
    describe(SO101.urdf.read_text(encoding='utf-8'))
    results: list[Any] = peer.set_parameters(
        f'{NS}/trajplan', [Parameter('start_positions', value=[0.0, 0.1, 0.2])])
    assert not results[0].successful
    assert 'start_positions: a start needs 5 joint angles, got 3' in results[0].reason
    results = peer.set_parameters(
        f'{NS}/trajplan', [Parameter('start_positions', value=[0.0, 0.1, 0.2, 0.3, 0.4])])
    assert results[0].successful


def test_a_description_that_start_positions_does_not_fit(start_node, peer) -> None:
    node = start_node('-r', '__ns:=/ur5_ns', '-p', 'start_positions:=[0.1, 0.2, 0.3, 0.4, 0.5]')
    try:
        pub = peer.node.create_publisher(String, '/ur5_ns/robot_description', LATCHED)
        pub.publish(String(data=PUBLISHED['ur5'].urdf.read_text(encoding='utf-8')))
        assert pub.wait_for_all_acked(Duration(seconds=30))
        # six joints to the automatic tip: taken, with all zeros as the start meanwhile
        node.wait_for(r'start_positions \[0.1, 0.2, 0.3, 0.4, 0.5\] does not fit the 6-joint '
                      r'chain: the start is all zeros')
        assert node.has(r'arm for the next plan: 6-joint arm \(shoulder_pan_joint')
        refused = peer.set_parameters('/ur5_ns/trajplan',
                                      [Parameter('start_positions', value=[0.1] * 5)])
        assert not refused[0].successful and 'needs 6 joint angles' in refused[0].reason
        taken = peer.set_parameters('/ur5_ns/trajplan',
                                    [Parameter('start_positions', value=[0.1] * 6)])
        assert taken[0].successful
    finally:
        assert node.stop() == 0, node.output
