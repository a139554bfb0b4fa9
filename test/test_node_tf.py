# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Goals and obstacles in frames the arm's URDF does not have, through tf2, over real DDS.

The node runs with tf2 (built from ``shared/tf2`` where it has no wheel, as ``tf2_env`` does);
the transforms come from broadcasters in processes of their own, as a camera calibration's and
a moving sensor's would.
"""
from __future__ import annotations

import json
from pathlib import Path
import re
import signal
import subprocess
import sys
import time
from typing import Iterator

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion, Vector3
from nav_msgs.srv import GetPlan
from node_under_test import ARM, LIVENESS_S, NodeProcess, trajectory_to, wait_until
import numpy as np
import pytest
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory
from trajplan_ros import plan
from trajplan_ros.kinematics.rotations import quaternion_of_turn, rotation_matrix
from trajplan_ros.motion.motion_profile import MotionProfile, Timing
from trajplan_ros.motion.trajectory import motion_states
from trajplan_ros.ros import outcomes
from trajplan_ros.tools.ros_client import plan_request, RosClient
from visualization_msgs.msg import Marker, MarkerArray

pytestmark = pytest.mark.dds

NS = '/tf_frames'
TARGET = np.array([0.151171, 0.19162, 0.172124])
#: The camera's calibration: its pose in base_link (a turn about a tilted axis, and a shift).
TURN = quaternion_of_turn((0.4, -0.3, 1.1))
SHIFT = np.array([0.25, -0.1, 0.45])
#: The moving sensor: at SHIFT + VELOCITY (t - t0), turned by TURN.
VELOCITY = np.array([0.05, -0.02, 0.01])
#: The node's transform_timeout, s: long enough for a loaded machine's broadcaster.
TIMEOUT = 2.0

#: A broadcaster process: ``static`` once, or ``moving`` at 50 Hz (linear in time, which tf's
#: interpolation between samples reproduces exactly).
BROADCASTER = r"""
import sys, rclpy
from geometry_msgs.msg import TransformStamped
from rclpy.executors import ExternalShutdownException
from tf2_ros import StaticTransformBroadcaster, TransformBroadcaster
kind, frame, t0 = sys.argv[1], sys.argv[2], float(sys.argv[3])
shift, velocity, turn = (list(map(float, sys.argv[k:k + n])) for k, n in ((4, 3), (7, 3), (10, 4)))
rclpy.init()
node = rclpy.create_node(f'{kind}_broadcaster')
def transform(stamp):
    t = TransformStamped()
    t.header.stamp, t.header.frame_id, t.child_frame_id = stamp, 'base_link', frame
    dt = 0.0 if kind == 'static' else rclpy.time.Time.from_msg(stamp).nanoseconds * 1e-9 - t0
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = (
        s + v * dt for s, v in zip(shift, velocity))
    r = t.transform.rotation
    r.x, r.y, r.z, r.w = turn
    return t
if kind == 'static':
    StaticTransformBroadcaster(node).sendTransform(transform(node.get_clock().now().to_msg()))
else:
    sender = TransformBroadcaster(node)
    node.create_timer(0.02, lambda: sender.sendTransform(
        transform(node.get_clock().now().to_msg())))
print('broadcasting', flush=True)
try:
    rclpy.spin(node)
except (KeyboardInterrupt, ExternalShutdownException):
    pass
"""


def in_camera(point: np.ndarray, shift: np.ndarray = SHIFT) -> np.ndarray:
    """Return a point of base_link in the camera frame."""
    return rotation_matrix(TURN).T @ (point - shift)


@pytest.fixture(scope='module')
def broadcast(tf2_env: dict[str, str]) -> Iterator:
    """Give a starter of broadcaster processes; each is stopped by its PID at the end."""
    started: list[subprocess.Popen] = []

    def start(kind: str, frame: str, t0: float = 0.0) -> None:
        args = [kind, frame, repr(t0), *(repr(float(v)) for v in (*SHIFT, *VELOCITY, *TURN))]
        proc = subprocess.Popen([sys.executable, '-c', BROADCASTER, *args], env=tf2_env,
                                stdout=subprocess.PIPE, text=True)
        started.append(proc)
        assert proc.stdout.readline().strip() == 'broadcasting'

    yield start
    for proc in started:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


@pytest.fixture(scope='module')
def planner(start_node, tf2_env: dict[str, str], broadcast,
            peer: RosClient) -> Iterator[NodeProcess]:
    """One node with tf2 and the collision check, beside a static camera_link."""
    node = start_node('-r', f'__ns:={NS}', '-p', 'collision_check:=true', '-p',
                      f'transform_timeout:={TIMEOUT}', '-p', 'max_planning_time:=30.0',
                      env=tf2_env)                    # (a busy machine's detours take long)
    assert 'need tf2' not in node.output
    broadcast('static', 'camera_link')
    wait_until(lambda: bool(call(peer, in_camera(TARGET), 'camera_link').plan.poses),
               what='the node to know camera_link')     # DDS has matched the /tf_static
    yield node
    assert node.stop() == 0, node.output


def trajectories(peer: RosClient):
    """Return the node's trajectories from now on (the inbox emptied of earlier tests')."""
    box = peer.inbox(JointTrajectory, f'{NS}/joint_trajectory')
    while not box.empty():
        box.get_nowait()
    return box


def end_of(box, goal: np.ndarray) -> np.ndarray:
    """Return the joint goal of the next trajectory in ``box`` that ends at ``goal``."""
    return np.array(trajectory_to(box, tuple(goal)).points[-1].positions)


def outcome(results, stamp: str) -> tuple[DiagnosticStatus, dict[str, str]]:
    """Return the plan_results status of the call stamped ``stamp``, and its values."""
    while True:
        status = results.get(timeout=LIVENESS_S)
        values = {v.key: v.value for v in status.values}
        if values['stamp'] == stamp:
            return status, values


def call(peer: RosClient, goal: np.ndarray, frame: str,
         stamp: tuple[int, int] = (0, 0)) -> GetPlan.Response:
    request = plan_request(tuple(goal))
    request.goal.header.frame_id = frame
    request.goal.header.stamp.sec, request.goal.header.stamp.nanosec = stamp
    return peer.call(GetPlan, f'{NS}/plan_trajectory', request)


def test_goals_in_the_camera_frame_reach_the_joint_goal_of_the_point_moved(
        planner: NodeProcess, peer: RosClient) -> None:
    box = trajectories(peer)
    assert call(peer, TARGET, 'base_link').plan.poses
    direct = end_of(box, TARGET)
    np.testing.assert_allclose(direct, plan(TARGET, np.zeros(5), seed=0).joint_goal, atol=1e-9)
    seen = in_camera(TARGET)
    answer = call(peer, seen, 'camera_link')                   # by the service
    assert answer.plan.poses and answer.plan.header.frame_id == 'base_link'
    np.testing.assert_allclose(end_of(box, TARGET), direct, atol=1e-6)
    mark = planner.mark()                                      # by goal_pose
    pose = PoseStamped(header=Header(frame_id='camera_link'))
    pose.pose.position, pose.pose.orientation.w = Point(x=seen[0], y=seen[1], z=seen[2]), 1.0
    peer.publish(PoseStamped, f'{NS}/goal_pose', pose)
    planner.wait_for(r"goal_pose #1 \(0\.151171, 0\.19162, 0\.172124\) m \(in 'camera_link'", mark)
    np.testing.assert_allclose(end_of(box, TARGET), direct, atol=1e-6)


def test_trajplan_goal_sends_a_stamped_goal_in_its_frame(planner: NodeProcess,
                                                         tf2_env: dict[str, str]) -> None:
    seen = in_camera(TARGET)
    done = subprocess.run([f'{sys.prefix}/bin/trajplan', 'goal', *map(str, seen), '--frame',
                           'camera_link', '--topic', f'{NS}/goal_pose', '--trajectory',
                           f'{NS}/joint_trajectory'], env=tf2_env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    assert f"in frame 'camera_link' on {NS}/goal_pose" in done.stdout
    angles = re.search(r'planned joint angles \[rad\]: (.*)', done.stdout).group(1)
    got = [float(v.split('=')[1]) for v in angles.split()]
    np.testing.assert_allclose(got, plan(TARGET, np.zeros(5), seed=0).joint_goal, atol=2e-6)


def test_a_moving_frame_is_taken_at_the_goal_s_stamp(planner: NodeProcess, peer: RosClient,
                                                     broadcast) -> None:
    box = trajectories(peer)
    t0 = time.time()
    broadcast('moving', 'sensor_link', t0)

    def sensor_known() -> bool:                 # TARGET, where the sensor is now: reachable
        now = SHIFT + VELOCITY * (time.time() - t0)
        return bool(call(peer, in_camera(TARGET, now), 'sensor_link').plan.poses)

    wait_until(sensor_known, what='the node to know sensor_link')   # DDS has matched the /tf
    when = peer.node.get_clock().now().nanoseconds + 300_000_000    # 0.3 s on: it waits
    stamp = (when // 10**9, when % 10**9)
    shift = SHIFT + VELOCITY * (when * 1e-9 - t0)          # the sensor then: TARGET is there
    assert call(peer, in_camera(TARGET, shift), 'sensor_link', stamp).plan.poses, \
        planner.output[-3000:]
    end = end_of(box, TARGET)                               # (1.5 cm off at any other time)
    np.testing.assert_allclose(ARM.tool(end[None])[0][0], TARGET, atol=1e-6)


def test_a_frame_that_never_comes_is_refused_within_the_timeout(planner: NodeProcess,
                                                                peer: RosClient) -> None:
    results = peer.inbox(DiagnosticStatus, f'{NS}/plan_results', qos=outcomes.QOS)
    clock = time.monotonic()
    assert not call(peer, TARGET, 'nowhere_link', (5, 7)).plan.poses
    took = time.monotonic() - clock
    status, values = outcome(results, '5.000000007')
    assert values['status'] == 'refused', values
    assert re.search(r"frame 'nowhere_link' has no transform to 'base_link' at stamp "
                     r'5\.000000007 within 2 s', status.message), status
    assert TIMEOUT <= took < LIVENESS_S
    assert call(peer, TARGET, 'base_link').plan.poses                 # the node lives on


def test_a_marker_in_the_camera_frame_blocks_the_motion_it_should(
        planner: NodeProcess, peer: RosClient) -> None:
    box = trajectories(peer)
    assert call(peer, in_camera(TARGET), 'camera_link').plan.poses   # camera_link is known
    start, goal = end_of(box, TARGET), np.array([0.2, 0.1, 0.15])
    free = plan(goal, start, seed=0)
    law = MotionProfile().time_law(ARM, 0.2)
    halfway = motion_states(free.start, free.joint_goal, law, Timing.INDEPENDENT,
                            np.array([free.motion_time_s / 2]))[0][0]
    x, y, z = in_camera(ARM.tool(halfway[None])[0][0])          # where the tool passes
    ball = Marker(header=Header(frame_id='camera_link'), ns='seen', id=1, type=Marker.SPHERE,
                  action=Marker.ADD, scale=Vector3(x=0.04, y=0.04, z=0.04),
                  pose=Pose(position=Point(x=x, y=y, z=z), orientation=Quaternion(w=1.0)))
    mark = planner.mark()
    peer.publish(MarkerArray, f'{NS}/collision_objects', MarkerArray(markers=[ball]))
    planner.wait_for(r'scene for the next plan: 1 obstacles from collision_objects; posed as '
                     r"'camera_link' stood on arrival, and kept there", mark)
    results = peer.inbox(DiagnosticStatus, f'{NS}/plan_results', qos=outcomes.QOS)
    assert call(peer, goal, 'base_link', (9, 1)).plan.poses
    _, values = outcome(results, '9.000000001')
    assert values['status'] == 'succeeded', values
    # not the direct motion, which passes through the ball: through a via point (which may
    # cost nothing where one joint's travel sets the time), or a slower one
    assert (values['via_points'] != '0'
            or float(values['motion_time_s']) > free.motion_time_s + 1e-3), values
    assert float(values['clearance_m']) >= 0.01 and 'seen/1' in values['clearance_pair'], values


def test_the_readme_camera_block_runs_as_pasted(start_node, tf2_env: dict[str, str],
                                                planner: NodeProcess) -> None:
    readme = (Path(__file__).resolve().parents[1] / 'README.md').read_text(encoding='utf-8')
    tag = ('needs tf2 built (test_node_tf runs this block against the node and a static '
           'camera_link)')
    block = readme.split(tag, 1)[1].split('```console\n', 1)[1].split('```', 1)[0]
    command, *shown = block.splitlines()
    node = start_node(env=tf2_env)                     # the README's: default names
    line = command.removeprefix('$ ').replace('.venv/bin/', f'{sys.prefix}/bin/')
    done = subprocess.run(line, shell=True, env=tf2_env, capture_output=True, text=True,
                          timeout=120)
    assert node.stop() == 0, node.output
    assert done.returncode == 0, done.stdout + done.stderr
    printed = done.stdout.splitlines()
    assert len(printed) == len(shown), (printed, shown)
    for line, pattern in zip(printed, shown):
        assert re.fullmatch('.*'.join(map(re.escape, pattern.split('...'))), line), (line, pattern)


def test_moveit_goals_in_the_camera_frame_are_planned_there(
        start_node, moveit_msgs_env: dict[str, str], tf2_env: dict[str, str],
        planner: NodeProcess) -> None:
    env = {**moveit_msgs_env, **{k: tf2_env[k] for k in ('PYTHONPATH', 'LD_LIBRARY_PATH')}}
    node = start_node('-r', '__ns:=/tf_moveit', '-r', '__node:=move_group', '-p',
                      'moveit_interfaces:=true', ready=False, env=env)
    node.wait_for(r'move_group\]: ready: ')
    specs = [{'position': in_camera(TARGET).tolist(), 'frame': 'camera_link'},
             {'position': TARGET.tolist(), 'frame': 'nowhere_link'}]
    done = subprocess.run([sys.executable, str(Path(__file__).with_name('moveit_client.py')),
                           '/tf_moveit/plan_kinematic_path', json.dumps(specs)], env=env,
                          capture_output=True, text=True, timeout=120)
    assert node.stop() == 0, node.output
    assert done.returncode == 0, done.stderr[-3000:]
    seen, nowhere = (json.loads(line) for line in done.stdout.splitlines())
    assert seen['code'] == 'SUCCESS', seen
    assert np.linalg.norm(ARM.tool(np.array([seen['positions'][-1]]))[0][0] - TARGET) <= 1e-3
    assert nowhere['code'] == 'FRAME_TRANSFORM_FAILURE', nowhere
    assert "frame 'nowhere_link' has no transform to 'base_link'" in nowhere['message']
