# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The planner node's parameters and names, over real DDS, through its parameter services.

The node here runs in a namespace with its trajectory remapped, as it would next to a
joint_trajectory_controller: every name it uses must follow.
"""
from __future__ import annotations

import math
import re
from typing import Iterator

from geometry_msgs.msg import Point
from nav_msgs.srv import GetPlan
from node_under_test import (check_servo_trajectory, HOPELESS_GOAL, LIVENESS_S, NodeProcess,
                             started_from, trajectory_to)
import numpy as np
import pytest
from rclpy.parameter import Parameter
from trajectory_msgs.msg import JointTrajectory
from trajplan_ros import ArmModel, paper_arm
from trajplan_ros.ros.settings import default_values
from trajplan_ros.tools.ros_client import plan_request, RosClient

pytestmark = pytest.mark.dds


NODE = '/arm_ns/trajplan'
TRAJECTORY = '/jtc/joint_trajectory'
PAPER = paper_arm()


@pytest.fixture(scope='module')
def planner(start_node) -> Iterator[NodeProcess]:
    node = start_node('-r', '__ns:=/arm_ns', '-r', f'joint_trajectory:={TRAJECTORY}')
    yield node
    assert node.stop() == 0, node.output


@pytest.fixture(scope='module')
def trajectories(planner: NodeProcess, peer: RosClient):
    return peer.inbox(JointTrajectory, TRAJECTORY)


def arm_parameters(arm: ArmModel, start: list[float]) -> list[Parameter]:
    a, alpha, d = arm.dh
    values = {f'arm.{k}': v.tolist() for k, v in (('a', a), ('alpha', alpha), ('d', d),
                                                  ('offset', arm.offset), ('lower', arm.lower),
                                                  ('upper', arm.upper))}
    values.update({'arm.sign': [int(s) for s in arm.sign],
                   'arm.joint_names': list(arm.joint_names),
                   'arm.planned': arm.planned, 'start_positions': start})
    return [Parameter(name, value=value) for name, value in values.items()]


def test_names_follow_the_namespace_and_remapping(planner, peer, trajectories) -> None:
    goal = (0.2, 0.0, 0.1)
    answer = peer.call(GetPlan, '/arm_ns/plan_trajectory', plan_request(goal))
    assert answer.plan.poses
    assert trajectory_to(trajectories, goal).points


def test_a_change_that_keeps_the_arm_does_not_log_a_new_arm(planner, peer) -> None:
    mark = planner.mark()
    results = peer.set_parameters(NODE, [Parameter('angular_velocity', value=0.3)])
    try:
        assert [r.successful for r in results] == [True]
        planner.wait_for(r'parameters set for the next plan: angular_velocity=0.3', mark)
        assert not planner.has('arm for the next plan', mark), planner.output
        mark = planner.mark()
        results = peer.set_parameters(NODE, [Parameter('arm.joint_names',
                                                       value=['a', 'b', 'c', 'd', 'e'])])
        assert [r.successful for r in results] == [True]
        planner.wait_for(r'arm for the next plan: 5-joint arm \(a, b, c, d, e\)', mark)
    finally:
        peer.set_parameters(NODE, [Parameter('angular_velocity', value=0.2),
                                   Parameter('arm.joint_names', value=list(PAPER.joint_names))])


def test_a_valid_change_takes_effect_for_the_next_plan(planner, peer, trajectories) -> None:
    names = ['base_yaw', 'shoulder', 'elbow', 'wrist', 'tool_roll']
    results = peer.set_parameters(NODE, [Parameter('angular_velocity', value=0.5),
                                         Parameter('arm.joint_names', value=names)])
    try:
        assert [r.successful for r in results] == [True, True], [r.reason for r in results]
        assert peer.get_parameters(NODE, ['angular_velocity', 'arm.joint_names']) == [0.5, names]
        planner.wait_for(r'parameters set for the next plan: .*arm.joint_names')

        goal = (0.1, 0.2, 0.2)
        mark = planner.mark()
        peer.publisher(Point, '/arm_ns/goal').publish(Point(x=goal[0], y=goal[1], z=goal[2]))
        _, start = started_from(planner, 'goal', goal, mark)
        check_servo_trajectory(trajectory_to(trajectories, goal), start, omega=0.5,
                               names=tuple(names))
    finally:
        peer.set_parameters(NODE, [Parameter('angular_velocity', value=0.2),
                                   Parameter('arm.joint_names', value=list(PAPER.joint_names))])


@pytest.mark.parametrize('name, value, reason', [
    ('angular_velocity', 0.0, r'out of range'),
    ('angular_velocity', math.nan, r'out of range'),
    ('angular_velocity', 'fast', r'Wrong parameter type'),
    ('population', 1, r'out of range'),
    ('sample_period', -0.1, r'out of range'),
    ('mode', 'sideways', r"mode must be one of free, radial, approach, got 'sideways'"),
    ('algorithm', 'sgd', r'algorithm must be one of iepso, '),
    ('base_frame', '', r'base_frame must not be empty'),
    ('arm.lower', [3.0, -1.5, -2.3, -2.3, -3.1], r'joint 1: lower limit 3.0 is above upper limit'),
    ('arm.a', [0.01, math.inf, 0.096, 0.027, 0.0], r'a has a non-finite value'),
    ('arm.sign', [1, 1, 1, 2, 1], r'sign must be \+1 or -1 per joint'),
    ('arm.joint_names', ['j1', 'j2', 'j3', 'j4'],
     r'joint_names must be 5 distinct non-empty names'),
    ('arm.planned', 6, r'planned joints must be between 2 and 5, got 6'),
    ('arm.alpha', [0.0, 0.0, 0.0], r'alpha needs 5 values'),
    ('start_positions', [0.0, 0.0, 0.0],
     r'start_positions: a start needs 5 joint angles \(or the 4 planned ones\), got 3'),
    ('profile', 'trapezoidal', r'trapezoidal profile needs an acceleration limit for joint '
                               r'joint1'),
    ('timing', 'later', r'timing must be one of independent, synchronized'),
    ('joint_limits_file', '/nonexistent/limits.yaml', r'cannot read joint limits'),
    ('max_acceleration', -1.0, r'out of range'),
])
def test_a_bad_value_is_rejected_with_its_reason(planner, peer, name, value, reason) -> None:
    before = peer.get_parameters(NODE, [name])
    [result] = peer.set_parameters(NODE, [Parameter(name, value=value)])
    assert not result.successful
    assert re.search(reason, result.reason), result.reason
    assert peer.get_parameters(NODE, [name]) == before


def test_an_arm_with_other_joints_is_set_in_one_atomic_call(planner, peer, trajectories) -> None:
    arm = ArmModel.from_dh(a=[0.0, 0.12, 0.10, 0.05], alpha=[math.pi / 2, 0.0, 0.0, 0.0],
                           d=[0.08, 0, 0, 0], lower=[-2.0] * 4, upper=[2.0] * 4,
                           joint_names=['q1', 'q2', 'q3', 'q4'], planned=4)
    change = arm_parameters(arm, [0.0] * 4)
    # one at a time, every step is an inconsistent arm: refused
    [first] = peer.set_parameters(NODE, change[:1])
    assert not first.successful and 'alpha needs 4 values' in first.reason
    [result] = peer.set_parameters(NODE, change, atomically=True)
    try:
        assert result.successful, result.reason
        goal = tuple(arm.tool(np.array([[0.5, 0.4, -0.6, 0.3]]))[0][0])
        mark = planner.mark()
        answer = peer.call(GetPlan, '/arm_ns/plan_trajectory', plan_request(goal, 1e-5))
        assert answer.plan.poses, planner.output
        _, start = started_from(planner, 'service call', goal, mark)
        np.testing.assert_allclose(start, 0.0, atol=1e-12)      # start_positions: new joints
        check_servo_trajectory(trajectory_to(trajectories, goal, arm=arm), start,
                               names=('q1', 'q2', 'q3', 'q4'))
    finally:
        [back] = peer.set_parameters(NODE, arm_parameters(PAPER, [0.0] * 5), atomically=True)
        assert back.successful, back.reason


def test_not_reached_gives_an_empty_plan_and_tolerance_counts(planner, peer) -> None:
    [short] = peer.set_parameters(NODE, [Parameter('max_iterations', value=30)])
    assert short.successful
    try:
        mark = planner.mark()
        answer = peer.call(GetPlan, '/arm_ns/plan_trajectory', plan_request(HOPELESS_GOAL))
        assert list(answer.plan.poses) == []
        planner.wait_for(r'service call #\d+ \(0.05, -0.05, -0.25\) m from .*: not_reached: '
                         r'goal not reached: best position error .* is above the tolerance '
                         r'1e-06 m', mark)
        # the same goal with a request tolerance of 10 cm counts as reached
        answer = peer.call(GetPlan, '/arm_ns/plan_trajectory', plan_request(HOPELESS_GOAL, 0.1))
        assert answer.plan.poses
        last = answer.plan.poses[-1].pose.position
        assert np.linalg.norm(np.subtract([last.x, last.y, last.z], HOPELESS_GOAL)) <= 0.1
    finally:
        peer.set_parameters(NODE, [Parameter('max_iterations', value=1000)])


@pytest.mark.parametrize('override, reason', [
    ('mode:=sideways', r'invalid parameters: mode must be one of free, radial'),
    ('angular_velocity:=-1.0', r'invalid parameters: .*angular_velocity'),
    ('arm.planned:=9', r'invalid parameters: .*arm.planned'),
])
def test_bad_parameters_at_startup_end_the_node_with_the_reason(start_node, override,
                                                                reason) -> None:
    node = start_node('-p', override, ready=False)
    assert node.proc.wait(timeout=LIVENESS_S) == 2
    node.stop()
    assert re.search(reason, node.output), node.output
    assert 'Traceback' not in node.output


def parameter_values(peer: RosClient, node: str) -> dict[str, object]:
    """Return every declared parameter of ``node`` as plain Python values (lists for arrays)."""
    names = list(default_values())
    values = peer.get_parameters(node, names)
    return {n: list(v) if not isinstance(v, (str, int, float)) else v
            for n, v in zip(names, values)}


def test_installed_params_file_starts_the_node_with_its_values(
        start_node, colcon_install, peer, tmp_path) -> None:
    installed = colcon_install.prefix / 'share' / 'trajplan_ros' / 'config' / 'params.yaml'
    node = start_node('-r', '__ns:=/from_file', '--params-file', str(installed))
    try:
        assert parameter_values(peer, '/from_file/trajplan') == default_values()
    finally:
        assert node.stop() == 0, node.output
    # the file is read, not ignored: a copy with other values gives the node those values
    changed = tmp_path / 'params.yaml'
    changed.write_text(installed.read_text(encoding='utf-8')
                       .replace('mode: free', 'mode: radial')
                       .replace('sample_period: 0.1', 'sample_period: 0.25'), encoding='utf-8')
    node = start_node('-r', '__ns:=/from_copy', '--params-file', str(changed))
    try:
        values = parameter_values(peer, '/from_copy/trajplan')
        assert (values['mode'], values['sample_period']) == ('radial', 0.25)
        assert {k: v for k, v in values.items() if k not in ('mode', 'sample_period')} == {
            k: v for k, v in default_values().items() if k not in ('mode', 'sample_period')}
    finally:
        assert node.stop() == 0, node.output


def test_a_jerk_limited_motion_is_published_with_its_derivatives(planner, peer,
                                                                 trajectories) -> None:
    change = [Parameter('profile', value='jerk_limited'),
              Parameter('timing', value='synchronized'),
              Parameter('max_acceleration', value=0.5), Parameter('max_jerk', value=2.0)]
    [result] = peer.set_parameters(NODE, change, atomically=True)
    try:
        assert result.successful, result.reason
        goal = (0.1, 0.2, 0.2)
        answer = peer.call(GetPlan, '/arm_ns/plan_trajectory', plan_request(goal))
        assert answer.plan.poses
        msg = trajectory_to(trajectories, goal)
        points = msg.points
        assert all(len(p.velocities) == len(p.accelerations) == 5 for p in points)
        assert list(points[-1].velocities) == [0.0] * 5
        assert list(points[-1].accelerations) == [0.0] * 5
        velocity = np.abs([p.velocities for p in points])
        assert velocity.max() <= 0.2 * (1 + 1e-9)                    # omega caps every joint
        assert np.abs([p.accelerations for p in points]).max() <= 0.5 * (1 + 1e-9)
    finally:
        [back] = peer.set_parameters(NODE, [Parameter('profile', value='servo'),
                                            Parameter('timing', value='independent'),
                                            Parameter('max_acceleration', value=0.0),
                                            Parameter('max_jerk', value=0.0)], atomically=True)
        assert back.successful, back.reason
