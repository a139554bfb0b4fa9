# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Collisions in the planner node (issue 29), over real DDS.

A scene sent as RViz markers on collision_objects changes the next plan, a bad one is refused,
collision_markers shows it.
"""
from __future__ import annotations

from typing import Iterator

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Point, Pose, Quaternion, Vector3
from nav_msgs.srv import GetPlan
from node_under_test import LIVENESS_S, NodeProcess
import numpy as np
import pytest
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory
from trajplan_ros import ArmCollision, CollisionWorld, paper_arm, plan, Scene
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.motion.motion_profile import MotionProfile, Timing
from trajplan_ros.motion.trajectory import motion_states
from trajplan_ros.ros.outcomes import outcome_values
from trajplan_ros.tools.ros_client import plan_request, RosClient
from visualization_msgs.msg import Marker, MarkerArray

pytestmark = pytest.mark.dds

NS = '/collisions'
TARGET = (0.151171, 0.19162, 0.172124)
ARM = paper_arm()


@pytest.fixture(scope='module')
def planner(start_node) -> Iterator[NodeProcess]:
    node = start_node('-r', f'__ns:={NS}', '-p', 'collision_check:=true')
    node.wait_for(r'collision check: 13 link pairs \(8 skipped, computed')
    yield node
    assert node.stop() == 0, node.output


def ball_on_the_way() -> Marker:
    """Return a 4 cm ball where the tool passes halfway through the unchecked plan."""
    first = plan(TARGET, seed=0)
    law = MotionProfile().time_law(ARM, 0.2)
    middle = motion_states(first.start, first.joint_goal, law, Timing.INDEPENDENT,
                           np.array([first.motion_time_s / 2]))[0][0]
    x, y, z = ARM.tool(middle[None])[0][0]
    return Marker(header=Header(frame_id='base_link'), ns='shelf', id=1, type=Marker.SPHERE,
                  action=Marker.ADD, scale=Vector3(x=0.04, y=0.04, z=0.04),
                  pose=Pose(position=Point(x=x, y=y, z=z), orientation=Quaternion(w=1.0)))


def planned(planner: NodeProcess, peer: RosClient) -> dict[str, str]:
    """Call the service for TARGET and return the outcome it published."""
    outcomes = peer.inbox(DiagnosticStatus, f'{NS}/plan_results')
    answer = peer.call(GetPlan, f'{NS}/plan_trajectory', plan_request(TARGET))
    while True:
        values = outcome_values(outcomes.get(timeout=LIVENESS_S))
        if values['request'] == 'service call' and values['x'] == repr(TARGET[0]):
            assert answer.plan.poses or values['status'] != 'succeeded'
            return values


def test_a_scene_sent_over_dds_changes_the_next_plan(planner: NodeProcess,
                                                     peer: RosClient) -> None:
    # the node's first plan starts upright (q = 0), as the library's does
    unchecked = plan(TARGET, seed=0)
    mark = planner.mark()
    peer.publish(MarkerArray, f'{NS}/collision_objects', MarkerArray(markers=[ball_on_the_way()]))
    planner.wait_for(r'scene for the next plan: 1 obstacles from collision_objects', mark)
    after = planned(planner, peer)
    assert after['status'] == 'succeeded', after
    assert float(after['motion_time_s']) > unchecked.motion_time_s + 1e-3
    assert float(after['clearance_m']) >= 0.01 and after['clearance_pair']
    assert after['via_points'] == '0'                     # a direct motion


def test_a_bad_marker_is_refused_and_the_scene_kept(planner: NodeProcess,
                                                    peer: RosClient) -> None:
    bad = ball_on_the_way()
    bad.scale.y = 0.05
    mark = planner.mark()
    peer.publish(MarkerArray, f'{NS}/collision_objects', MarkerArray(markers=[bad]))
    planner.wait_for(r'collision_objects refused, scene kept: marker shelf/1: a sphere needs '
                     r'scale x = y = z', mark)


def test_collision_markers_show_the_scene_and_the_spheres(planner: NodeProcess,
                                                          peer: RosClient) -> None:
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    box = peer.inbox(MarkerArray, f'{NS}/collision_markers', qos=latched)
    markers = box.get(timeout=LIVENESS_S).markers
    assert markers[0].action == Marker.DELETEALL
    assert {m.ns for m in markers[1:]} <= {'scene', 'arm_spheres'}
    assert any(m.ns == 'arm_spheres' for m in markers)


#: The README's box: no direct motion from q = 0 to TARGET is free.
BOX_SIZE, BOX_AT = (0.13, 0.08, 0.15), (0.056, 0.098, 0.158)


def test_a_goal_behind_a_box_is_published_as_one_motion_through_its_via_point(
        start_node, peer: RosClient, tmp_path) -> None:
    scene = tmp_path / 'box.yaml'
    scene.write_text(f'obstacles:\n  - {{id: box, type: box, dimensions: {list(BOX_SIZE)}, '
                     f'position: {list(BOX_AT)}}}\n')
    node = start_node('-r', '__ns:=/behind_a_box', '-p', 'collision_check:=true',
                      '-p', f'scene_file:={scene}')
    try:
        trajectories = peer.inbox(JointTrajectory, '/behind_a_box/joint_trajectory')
        outcomes = peer.inbox(DiagnosticStatus, '/behind_a_box/plan_results')
        peer.call(GetPlan, '/behind_a_box/plan_trajectory', plan_request(TARGET))
        outcome = outcomes.get(timeout=LIVENESS_S)
        message = trajectories.get(timeout=LIVENESS_S)
    finally:
        assert node.stop() == 0, node.output
    values = outcome_values(outcome)
    assert values['status'] == 'succeeded' and values['via_points'] == '1', outcome.message
    # the same plan by the library on the same shapes, from the node's start (q = 0): its via
    # point is a point of the message
    urdf = tmp_path / 'paper_arm.urdf'
    urdf.write_text(urdf_xml(ARM, velocity=0.2))
    world = CollisionWorld(ArmCollision.from_urdf(urdf, ARM), Scene.from_file(scene), 0.01)
    mine = plan(TARGET, start=np.zeros(5), seed=0, world=world, max_planning_time=1.0)
    assert mine.message.split(', least')[0] == outcome.message.split(', least')[0]
    points = np.array([p.positions for p in message.points])
    assert np.min(np.max(np.abs(points - mine.via_points[0]), axis=1)) < 1e-9
    np.testing.assert_allclose(points[-1], mine.joint_goal, atol=1e-9)
