# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The planner node over real DDS: the colcon-installed planner_node in its own process.

Everything here talks to the node the way another ROS 2 process would: the service, the goal
and joint_states topics, the published trajectory and the node's log lines.
"""
from __future__ import annotations

import os
import queue
import re
import signal
import subprocess
import sys
import time
from typing import Iterator

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Point
from nav_msgs.srv import GetPlan
from node_under_test import (ARM, check_servo_trajectory, fmt, HOPELESS_GOAL, Install,
                             LIVENESS_S, NodeProcess, OMEGA, rotation, started_from,
                             trajectory_to, wait_until)
import numpy as np
import pytest
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory
from trajplan_ros import plan
from trajplan_ros.ros import outcomes
from trajplan_ros.tools.bench.cases import PAPER_TARGET
from trajplan_ros.tools.ros_client import plan_request, RosClient

pytestmark = pytest.mark.dds


PAPER_GOAL = tuple(PAPER_TARGET.tolist())


@pytest.fixture(scope='module')
def planner(start_node) -> Iterator[NodeProcess]:
    """One planner node with default parameters, shared by this module's tests."""
    node = start_node()
    yield node
    assert node.stop() == 0, node.output


@pytest.fixture(scope='module')
def trajectories(planner: NodeProcess, peer: RosClient):
    return peer.inbox(JointTrajectory, '/joint_trajectory')


def test_colcon_install_has_the_ament_layout(colcon_install: Install) -> None:
    prefix = colcon_install.prefix
    assert (prefix / 'share/ament_index/resource_index/packages/trajplan_ros').is_file()
    assert (prefix / 'share/trajplan_ros/package.xml').is_file()
    assert colcon_install.executable.is_file()
    assert os.access(colcon_install.executable, os.X_OK)
    # `ros2 run` looks the package up in the ament index, then runs lib/<package>/<executable>
    lookup = ('from ament_index_python.packages import get_package_prefix;'
              "print(get_package_prefix('trajplan_ros'))")
    found = subprocess.run([sys.executable, '-c', lookup], capture_output=True, text=True,
                           env=colcon_install.env(os.environ), timeout=LIVENESS_S)
    assert found.stdout.strip() == str(prefix), found.stderr


def test_service_call_reaches_the_goal_and_publishes(planner, peer, trajectories) -> None:
    mark = planner.mark()
    answer = peer.call(GetPlan, '/plan_trajectory', plan_request(PAPER_GOAL, tolerance=1e-4))
    poses = answer.plan.poses
    assert poses, planner.output
    assert answer.plan.header.frame_id == 'base_link'
    last = poses[-1].pose.position
    assert np.linalg.norm(np.array([last.x, last.y, last.z]) - PAPER_GOAL) <= 1e-4

    # the published trajectory ends at the planned joint angles: the ones plan() finds from
    # the same start with the same (default) seed
    _, start = started_from(planner, 'service call', PAPER_GOAL, mark)
    msg = trajectory_to(trajectories, PAPER_GOAL, tol=1e-4)
    end = check_servo_trajectory(msg, start)
    expected = plan(PAPER_GOAL, start, seed=0, tolerance=1e-4)
    np.testing.assert_allclose(end, expected.joint_goal, atol=1e-9)

    # one pose per trajectory point, from forward kinematics
    assert len(poses) == len(msg.points)
    q = np.array([p.positions for p in msg.points])
    tool, axis = ARM.tool(q)
    frames = ARM.frames(q)[:, -1]
    for k, pose in enumerate(poses):
        assert pose.header.frame_id == 'base_link'
        p, o = pose.pose.position, pose.pose.orientation
        np.testing.assert_allclose([p.x, p.y, p.z], tool[k], atol=1e-12)
        assert np.linalg.norm([o.x, o.y, o.z, o.w]) == pytest.approx(1.0)
        np.testing.assert_allclose(rotation(o), frames[k, :3, :3], atol=1e-9)
        np.testing.assert_allclose(rotation(o)[:, 2], axis[k], atol=1e-9)


def test_goal_topic_yields_a_controller_ready_trajectory(planner, peer, trajectories) -> None:
    goal = (0.1, 0.1, 0.2)
    mark = planner.mark()
    peer.publisher(Point, '/goal').publish(Point(x=goal[0], y=goal[1], z=goal[2]))
    _, start = started_from(planner, 'goal', goal, mark)
    end = check_servo_trajectory(trajectory_to(trajectories, goal), start)
    tool, _ = ARM.tool(end[None, :])
    assert np.linalg.norm(tool[0] - goal) <= 1e-6                 # the default tolerance
    np.testing.assert_array_equal(end[ARM.planned:], start[ARM.planned:])   # joint5 held


def test_joint_states_give_the_start(planner, peer, trajectories) -> None:
    q_start = np.array([0.3, -0.2, 0.4, 0.1, 0.5])
    states = peer.publisher(JointState, '/joint_states')
    # the names are matched, not the order; other robots' joints are ignored
    order = [4, 2, 0, 1, 3]
    state = JointState(name=['gripper'] + [ARM.joint_names[i] for i in order],
                       position=[9.0] + q_start[order].tolist())
    # joint_states come again and again (the node takes them best effort) and travel apart
    # from the service: publish, and probe with a goal refused at once (its log line still
    # names the start), until the state has arrived
    probe = (float('nan'), 0.0, 0.0)
    deadline = time.monotonic() + LIVENESS_S
    while True:
        states.publish(state)
        mark = planner.mark()
        assert not peer.call(GetPlan, '/plan_trajectory', plan_request(probe)).plan.poses
        _, start = started_from(planner, 'service call', probe, mark)
        if np.allclose(start, q_start, atol=1e-6) or time.monotonic() > deadline:
            break
    goal = (0.2, 0.0, 0.1)
    mark = planner.mark()
    assert peer.call(GetPlan, '/plan_trajectory', plan_request(goal)).plan.poses
    _, start = started_from(planner, 'service call', goal, mark)
    np.testing.assert_allclose(start, q_start, atol=1e-6)
    end = check_servo_trajectory(trajectory_to(trajectories, goal), q_start)
    assert end[4] == pytest.approx(0.5)

    # a message with NaN is refused with the reason; the start stays the last good one
    mark = planner.mark()
    nan_state = JointState(name=list(ARM.joint_names), position=[0.0, float('nan'), 0, 0, 0])
    wait_until(lambda: states.publish(nan_state) or planner.has(
        r'ignored joint_states: non-finite position for joint2', mark), what='the NaN refused')
    mark = planner.mark()
    assert peer.call(GetPlan, '/plan_trajectory', plan_request(goal)).plan.poses
    _, start = started_from(planner, 'service call', goal, mark)
    np.testing.assert_allclose(start, q_start, atol=1e-6)


def test_bad_goals_publish_nothing_and_the_node_lives_on(planner, peer, trajectories) -> None:
    mark = planner.mark()
    goals = peer.publisher(Point, '/goal')
    goals.publish(Point(x=float('nan'), y=0.0, z=0.1))
    planner.wait_for(r'goal #\d+ \(nan, 0, 0.1\) m from .*: rejected: goal has a non-finite', mark)
    goals.publish(Point(x=1.0, y=0.0, z=0.0))
    planner.wait_for(r'goal #\d+ \(1, 0, 0\) m from .*: rejected: goal is 1.0000 m from the base, '
                     r"beyond the arm's reach", mark)
    answer = peer.call(GetPlan, '/plan_trajectory', plan_request((0.0, float('inf'), 0.2)))
    assert list(answer.plan.poses) == []                 # empty plan: failure, as in nav
    planner.wait_for(r'service call #\d+ \(0, inf, 0.2\) m from .*: rejected: ', mark)
    assert planner.proc.poll() is None

    # still planning; of all plans since the bad goals only this one published a trajectory
    good = (0.2, 0.1, 0.15)
    answer = peer.call(GetPlan, '/plan_trajectory', plan_request(good))
    assert answer.plan.poses
    trajectory_to(trajectories, good)
    planner.wait_for(rf'service call #\d+ {fmt(good)} m from .*; published ', mark)
    published = [line for line in planner.lines[mark:] if '; published ' in line]
    assert len(published) == 1, published
    assert 'Traceback' not in planner.output


def trajplan(*args: str) -> subprocess.CompletedProcess:
    """Run the ``trajplan`` command in the tests' DDS domain, as a user in a venv would."""
    return subprocess.run([sys.executable, '-m', 'trajplan_ros.tools.cli', *args],
                          capture_output=True, text=True, timeout=3 * LIVENESS_S)


def test_trajplan_call_plans_through_the_service(planner) -> None:
    goal = (0.18, 0.05, 0.12)
    mark = planner.mark()
    done = trajplan('call', *map(str, goal), '--trajectory')
    assert done.returncode == 0, done.stdout + done.stderr
    _, start = started_from(planner, 'service call', goal, mark)
    expected = plan(goal, start, seed=0)
    angles = re.search(r'planned joint angles \[rad\]: (.*)', done.stdout).group(1)
    got = [float(v.split('=')[1]) for v in angles.split()]
    np.testing.assert_allclose(got, expected.joint_goal, atol=1e-6)     # printed to 6 decimals
    assert float(re.search(r'position error: (\S+) m', done.stdout).group(1)) <= 1e-6
    # a goal the node refuses: the node's reason on stderr (from plan_results), exit status 1
    done = trajplan('call', '1.0', '0.0', '0.0')
    assert done.returncode == 1, done.stdout + done.stderr
    assert re.search(r'^trajplan: not planned: rejected: goal is 1\.0000 m from the base, '
                     r"beyond the arm's reach", done.stderr, re.M), done.stderr
    done = trajplan('call', '0.17', '0.06', '0.12', '--frame', 'map')
    called = "calling plan_trajectory, goal (0.17, 0.06, 0.12) m in frame 'map'"
    assert done.returncode == 1 and called in done.stdout, done.stdout + done.stderr
    assert "not planned: refused: frame 'map' is not a link of the robot" in done.stderr
    mark = planner.mark()                     # --plan-only: compute_plan, the answer alone
    done = trajplan('call', '0.17', '0.06', '0.12', '--plan-only')
    assert done.returncode == 0 and 'calling compute_plan' in done.stdout, done.stdout
    planner.wait_for(r'compute_plan call #\d+ \(0.17, 0.06, 0.12\) m .*answered, not sent', mark)


def test_trajplan_goal_publishes_a_goal_the_node_plans(planner) -> None:
    goal = (0.12, -0.08, 0.16)
    mark = planner.mark()
    done = trajplan('goal', *map(str, goal), '--trajectory')
    assert done.returncode == 0, done.stdout + done.stderr
    assert 'published goal (0.12, -0.08, 0.16) m on goal' in done.stdout
    planner.wait_for(rf'\]: goal #\d+ {fmt(goal)} m from .*; published ', mark)
    assert re.search(r'^succeeded: reached in \d+\.\d{4} s of motion', done.stdout, re.M)
    assert re.search(r'JointTrajectory on joint_trajectory: \d+ points', done.stdout)
    # a goal the node refuses: its reason on stderr, exit status 1
    done = trajplan('goal', '0.0', '0.0', '-0.9')
    assert done.returncode == 1, done.stdout + done.stderr
    assert re.search(r'^trajplan: not planned: rejected: goal is 0\.9\d+ m from the base',
                     done.stderr, re.M), done.stderr


def outcomes_of(box, names: set[str], timeout: float = LIVENESS_S) -> dict[str, list]:
    """Collect the outcomes in ``box`` until every job in ``names`` has one; by job name."""
    found: dict[str, list] = {}
    deadline = time.monotonic() + timeout
    while not names <= set(found) and time.monotonic() < deadline:
        try:
            msg = box.get(timeout=0.1)
        except queue.Empty:
            continue
        found.setdefault(msg.name.split(': ', 1)[1], []).append(
            (msg.level, msg.message, outcomes.outcome_values(msg)))
    assert names <= set(found), (sorted(names - set(found)), found)
    return found


def test_every_goal_and_call_has_one_outcome_with_its_reason(start_node, peer) -> None:
    node = start_node('-r', '__ns:=/outcomes', '--log-level', 'outcomes.trajplan:=debug')
    box = peer.inbox(DiagnosticStatus, '/outcomes/plan_results', qos=outcomes.QOS)
    # refused before planning, told apart by their stamps
    wrong_frame = plan_request((0.2, 0.1, 0.15))
    wrong_frame.goal.header.frame_id = 'world'
    wrong_frame.goal.header.stamp.sec, wrong_frame.goal.header.stamp.nanosec = 7, 11
    negative = plan_request((0.2, 0.1, 0.15), tolerance=-1.0)
    negative.goal.header.stamp.sec = 8
    for request in (wrong_frame, negative):
        assert not peer.call(GetPlan, '/outcomes/plan_trajectory', request).plan.poses
    # a goal that keeps the node busy (until max_planning_time), then three: two superseded
    goals = peer.publisher(Point, '/outcomes/goal')
    goals.publish(Point(x=HOPELESS_GOAL[0], y=HOPELESS_GOAL[1], z=HOPELESS_GOAL[2]))
    node.wait_for(r'planning goal #1 ')
    for x in (0.11, 0.12, 0.13):
        goals.publish(Point(x=x, y=0.05, z=0.2))
    node.wait_for(r'goal #4 \(0.13, 0.05, 0.2\) m from .*: reached')
    names = {'service call #1', 'service call #2', 'goal #1', 'goal #2', 'goal #3', 'goal #4'}
    found = outcomes_of(box, names)
    assert node.stop() == 0, node.output
    assert set(found) == names and all(len(found[n]) == 1 for n in names), found
    by_stamp = {v['stamp']: (level, message, v) for name in names if name.startswith('service')
                for level, message, v in found[name]}
    level, message, values = by_stamp['7.000000011']
    assert (level, values['status']) == (DiagnosticStatus.ERROR, 'refused')
    assert values['request'] == 'service call'
    assert "frame 'world' is not a link of the robot" in message
    assert (values['x'], values['y'], values['z']) == ('0.2', '0.1', '0.15')
    assert by_stamp['8.000000000'][2]['status'] == 'refused'
    assert 'tolerance -1.0 m is not allowed' in by_stamp['8.000000000'][1]
    assert found['goal #1'][0][2]['status'] in ('not_reached', 'timed_out')
    ends = [found[f'goal #{n}'][0] for n in (2, 3, 4)]
    assert [v['status'] for _, _, v in ends] == ['superseded', 'superseded', 'succeeded']
    assert [level for level, _, _ in ends] == [DiagnosticStatus.WARN, DiagnosticStatus.WARN,
                                               DiagnosticStatus.OK]
    assert float(ends[2][2]['motion_time_s']) > 0 and ends[2][2]['stamp'] == ''


def test_trajplan_call_without_a_node_times_out_with_the_reason() -> None:
    done = trajplan('call', '0.1', '0.1', '0.1', '--service', '/nobody/plan_trajectory',
                    '--timeout', '1')
    assert done.returncode == 1
    assert 'no service /nobody/plan_trajectory within 1 s: is planner_node running, and with ' \
           'the same ROS_DOMAIN_ID' in done.stderr
    assert 'Traceback' not in done.stderr


def test_simultaneous_service_calls_are_all_answered(planner, peer) -> None:
    goals = [(0.15, 0.15, 0.15), (0.2, -0.1, 0.1), (0.1, 0.2, 0.2), (0.25, 0.0, 0.05)]
    futures = [peer.call_async(GetPlan, '/plan_trajectory', plan_request(g)) for g in goals]
    # the node answers its parameter services meanwhile
    assert peer.get_parameters('/trajplan', ['angular_velocity']) == [OMEGA]
    for goal, future in zip(goals, futures):
        poses = peer.result(future).plan.poses
        assert poses, planner.output
        last = poses[-1].pose.position
        np.testing.assert_allclose([last.x, last.y, last.z], goal, atol=1e-6)


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
def test_signal_mid_plan_ends_the_node_cleanly_and_answers_the_call(start_node, peer,
                                                                    sig) -> None:
    # a plan that runs for a minute: a goal never reached, by plain PSO, a big swarm, no cap
    node = start_node('-r', '__ns:=/sig', '-p', 'algorithm:=pso', '-p', 'population:=5000',
                      '-p', 'max_iterations:=1000000', '-p', 'max_planning_time:=60.0',
                      '--log-level', 'sig.trajplan:=debug')
    results = peer.inbox(DiagnosticStatus, '/sig/plan_results', qos=outcomes.QOS)
    while not results.empty():                          # the other signal's run
        results.get_nowait()
    pending = peer.call_async(GetPlan, '/sig/plan_trajectory', plan_request(HOPELESS_GOAL))
    node.wait_for(r'planning service call #1 ')        # the worker plans this call
    peer.publisher(Point, '/sig/goal').publish(Point(x=0.1, y=0.1, z=0.2))    # queued behind it
    node.wait_for(r'queued goal #1 ')
    node.proc.send_signal(sig)
    began = time.monotonic()
    code = node.proc.wait(timeout=LIVENESS_S)
    elapsed = time.monotonic() - began
    node.stop()
    assert code == 0, node.output
    assert 'Traceback' not in node.output
    assert list(peer.result(pending).plan.poses) == []                  # answered, empty
    assert node.has(r'service call #1 .* m: unplanned: shutting down')  # stopped mid-plan
    assert node.has(r'goal #1 .* m: unplanned: shutting down')          # the queued goal
    assert not node.has(r'published ')
    found = outcomes_of(results, {'service call #1', 'goal #1'})
    assert {name: [v['status'] for _, _, v in found[name]] for name in found} == {
        'service call #1': ['shut_down'], 'goal #1': ['shut_down']}
    print(f'{sig.name}: exited {elapsed:.3f} s after the signal')
