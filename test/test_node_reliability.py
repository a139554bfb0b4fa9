# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The node never loses a request: over real DDS, with small sizes (full sizes: the stress bench).

Every test asserts counts and answers, never the wall clock.
"""
from __future__ import annotations

import re
import signal
from typing import Iterator

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Point
from nav_msgs.msg import Path
from nav_msgs.srv import GetPlan
from node_under_test import fmt, HOPELESS_GOAL, LIVENESS_S, NodeProcess, wait_until
import numpy as np
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from sensor_msgs.msg import JointState
from trajplan_ros import paper_arm
from trajplan_ros.tools.bench.cases import PAPER_TARGET
from trajplan_ros.tools.ros_client import KEEP_ALL, plan_request, RosClient

pytestmark = pytest.mark.dds


ARM = paper_arm()


def goals(count: int, seed: int) -> list[tuple[float, float, float]]:
    """Tool positions of random in-limit configurations, rounded so log lines are unique."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(ARM.lower, ARM.upper, (count, ARM.n_joints))
    return [tuple(float(v) for v in np.round(p, 5)) for p in ARM.tool(q)[0]]


def ends_at(path: Path, goal: tuple[float, float, float], tol: float = 1e-6) -> bool:
    last = path.poses[-1].pose.position
    return bool(np.linalg.norm(np.subtract([last.x, last.y, last.z], goal)) <= tol)


@pytest.fixture()
def lone_node(start_node, request) -> Iterator[NodeProcess]:
    """Start a node of its own in a namespace named after the test."""
    node = start_node('-r', f'__ns:=/{request.node.name.split("[")[0][5:]}')
    yield node
    assert node.stop() == 0, node.output


def test_a_lone_call_is_answered_with_nothing_else_happening(start_node, peer) -> None:
    # the answer is handed from the worker thread to the waiting coroutine: nothing but that
    # hand-over can wake the executor here (no other call, goal, state or parameter traffic,
    # and the diagnostics timer is an hour away), so a missed wake-up would hang this call
    ns = '/lone'
    node = start_node('-r', f'__ns:={ns}', '-p', 'diagnostic_updater.period:=3600.0')
    answer = peer.call(GetPlan, f'{ns}/plan_trajectory', plan_request((0.2, 0.1, 0.15)))
    assert ends_at(answer.plan, (0.2, 0.1, 0.15))
    assert node.stop() == 0, node.output


def test_concurrent_callers_are_all_answered_once_in_order(lone_node) -> None:
    ns = '/concurrent_callers_are_all_answered_once_in_order'
    clients = [RosClient(f'caller{k}') for k in range(3)]
    try:
        asked = {k: goals(8, seed=k) for k in range(3)}
        # one answered call each first: requests a new client writes before DDS has matched
        # it with the service are lost on the way, before the node (Fast DDS discovery race)
        for k, client in enumerate(clients):
            client.call(GetPlan, f'{ns}/plan_trajectory', plan_request(asked[k][0]))
        futures = {k: [c.call_async(GetPlan, f'{ns}/plan_trajectory', plan_request(g))
                       for g in asked[k]] for k, c in enumerate(clients)}
        for k, client in enumerate(clients):
            for goal, future in zip(asked[k], futures[k]):
                assert ends_at(client.result(future).plan, goal), lone_node.output
    finally:
        for client in clients:
            client.close()
    # the node logs a call after handing over its answer: wait for the last line
    pattern = r'\]: service call #(\d+) \('
    wait_until(lambda: len(lone_node.matches(pattern)) >= 27, what='27 calls logged')
    numbers = [int(m.group(1)) for m in lone_node.matches(pattern)]
    assert sorted(numbers) == list(range(1, 28))         # 3 + 24 calls, each planned once
    assert numbers == sorted(numbers)                    # in arrival order


def test_calls_beyond_the_queue_and_at_shutdown_are_answered(start_node, peer) -> None:
    # the first call plans for a long time (a goal never reached, a big swarm, a long deadline);
    # two more wait, the rest are beyond max_queued_calls
    node = start_node('-r', '__ns:=/queue', '-p', 'max_queued_calls:=2', '-p', 'algorithm:=pso',
                      '-p', 'population:=5000', '-p', 'max_iterations:=1000000',
                      '-p', 'max_planning_time:=60.0', '--log-level', 'queue.trajplan:=debug')
    first = peer.call_async(GetPlan, '/queue/plan_trajectory', plan_request(HOPELESS_GOAL))
    node.wait_for(r'planning service call #1 ')
    rest = [peer.call_async(GetPlan, '/queue/plan_trajectory', plan_request(g))
            for g in goals(5, seed=7)]
    full = r'refused: 2 calls are waiting already \(max_queued_calls\)'
    wait_until(lambda: len(node.matches(full)) >= 3, what='three calls refused')
    assert len(node.matches(full)) == 3
    node.proc.send_signal(signal.SIGINT)
    assert node.proc.wait(timeout=LIVENESS_S) == 0, node.output
    node.stop()                                          # every log line read
    answers = [peer.result(f) for f in [first, *rest]]
    assert all(list(a.plan.poses) == [] for a in answers)            # every one answered, empty
    assert len(node.matches(r'service call #\d+ .*: unplanned: shutting down')) >= 3
    assert 'Traceback' not in node.output


def test_answers_held_by_a_late_client_all_arrive(lone_node) -> None:
    # 12 answers wait in the reader of a client whose executor takes none of them yet (as when
    # the node answers every queued call at once at shutdown): with the services default QoS
    # (KEEP_LAST 10) DDS drops the oldest two; with the clients' KEEP_ALL every one arrives
    name = '/answers_held_by_a_late_client_all_arrive/plan_trajectory'
    context = rclpy.Context()
    rclpy.init(context=context)
    executor = SingleThreadedExecutor(context=context)
    late = None
    try:
        late = rclpy.create_node('late_client', context=context)
        executor.add_node(late)
        client = late.create_client(GetPlan, name, qos_profile=KEEP_ALL)
        assert client.wait_for_service(timeout_sec=LIVENESS_S)
        # one answered call first, so that DDS has matched this client with the service
        first = client.call_async(plan_request(PAPER_TARGET))
        wait_until(lambda: executor.spin_once(timeout_sec=0.05) or first.done(),
                   what='the first answer')
        asked = goals(12, seed=11)
        futures = [client.call_async(plan_request(g)) for g in asked]
        wait_until(lambda: len(lone_node.matches(r'service call #\d+ .*; planned in')) == 13,
                   what='13 calls answered')
        wait_until(lambda: executor.spin_once(timeout_sec=0.05) or all(f.done() for f in futures),
                   what='12 answers taken')
        assert all(ends_at(f.result().plan, g) for f, g in zip(futures, asked))
    finally:
        executor.shutdown()
        if late is not None:
            late.destroy_node()
        rclpy.try_shutdown(context=context)


def test_every_goal_of_a_flood_is_accounted_for(lone_node, peer) -> None:
    ns = '/every_goal_of_a_flood_is_accounted_for'
    sent = goals(60, seed=11)
    diagnostics: list[DiagnosticArray] = []
    peer.node.create_subscription(DiagnosticArray, '/diagnostics', diagnostics.append, 10)
    publisher = peer.node.create_publisher(Point, f'{ns}/goal', KEEP_ALL)
    peer.publisher(Point, f'{ns}/goal')                  # waits until the node subscribes
    # the first goal alone, until the node has planned it: seeing the node's reader does not
    # mean it has matched this publisher yet, and goals written before that never arrive
    publisher.publish(Point(x=sent[0][0], y=sent[0][1], z=sent[0][2]))
    lone_node.wait_for(rf'\]: goal #1 {fmt(sent[0])} m from')
    for g in sent[1:]:
        publisher.publish(Point(x=g[0], y=g[1], z=g[2]))
    settled = {}
    for g in sent:
        m = lone_node.wait_for(rf'\]: (?:(goal) #\d+ {fmt(g)} m from|(superseded) goal #\d+ '
                               rf'{fmt(g)} m: )')
        settled[g] = m.group(1) or m.group(2)
    assert len(settled) == 60
    superseded = list(settled.values()).count('superseded')
    # diagnostics count the same: received = planned + superseded + failed = sent
    wanted = {'goals_received': '60', 'goals_superseded': str(superseded)}

    def counted() -> bool:
        for array in reversed(diagnostics):
            for status in array.status:
                values = {kv.key: kv.value for kv in status.values}
                matches = all(values.get(k) == v for k, v in wanted.items())
                if status.name.startswith(ns) and matches:
                    ends = ('goals_planned', 'goals_superseded', 'goals_failed')
                    return sum(int(values[k]) for k in ends) == 60
        return False

    wait_until(counted, what='diagnostics counting every goal')


def test_refusals_before_planning(lone_node, peer) -> None:
    ns = '/refusals_before_planning'
    for tolerance, reason in ((-1.0, 'tolerance -1.0 m is not allowed'),
                              (float('inf'), 'tolerance inf m is not allowed')):
        request = plan_request((0.2, 0.1, 0.15), tolerance)
        answer = peer.call(GetPlan, f'{ns}/plan_trajectory', request)
        assert list(answer.plan.poses) == []
        lone_node.wait_for(re.escape(reason))
    request = plan_request((0.2, 0.1, 0.15))
    request.goal.header.frame_id = 'map'
    assert list(peer.call(GetPlan, f'{ns}/plan_trajectory', request).plan.poses) == []
    lone_node.wait_for(r"refused: frame 'map' is not a link of the robot; known frames: "
                       r'base_link, ')
    request.goal.header.frame_id = 'base_link'                       # our frame: planned
    assert ends_at(peer.call(GetPlan, f'{ns}/plan_trajectory', request).plan, (0.2, 0.1, 0.15))
    assert 'Traceback' not in lone_node.output and 'ERROR' not in lone_node.output


def test_work_is_bounded(start_node, peer) -> None:
    node = start_node('-r', '__ns:=/bounded', '-p', 'angular_velocity:=0.001',
                      '-p', 'sample_period:=0.001')
    try:
        answer = peer.call(GetPlan, '/bounded/plan_trajectory', plan_request((0.2, 0.1, 0.15)))
        assert list(answer.plan.poses) == []
        m = node.wait_for(r'refused: the trajectory would need (\d+) points, more than '
                          r'max_trajectory_points 10000')
        assert int(m.group(1)) > 10000
    finally:
        assert node.stop() == 0, node.output


def test_joint_states_problems_are_reported_and_the_start_names_its_sources(
        lone_node, peer) -> None:
    ns = '/joint_states_problems_are_reported_and_the_start_names_its_sources'
    states = peer.publisher(JointState, f'{ns}/joint_states')
    bad = {
        'duplicate name joint1': JointState(name=['joint1', 'joint1'], position=[0.1, 0.2]),
        '2 names but 1 positions': JointState(name=['joint1', 'joint2'], position=[0.1]),
        "names none of the arm's joints: got Joint1; expected joint1, joint2, joint3, "
        'joint4, joint5': JointState(name=['Joint1'], position=[0.1]),
    }
    for text, msg in bad.items():
        mark = lone_node.mark()
        wait_until(lambda: states.publish(msg) or lone_node.has(re.escape(text), mark),
                   what=text)
    # a partial state: the start of the next plan says where each joint came from
    partial = JointState(name=['joint2'], position=[0.25])
    probe = (float('nan'), 0.0, 0.0)

    def arrived() -> bool:
        states.publish(partial)
        mark = lone_node.mark()
        peer.call(GetPlan, f'{ns}/plan_trajectory', plan_request(probe))
        logged = lone_node.wait_for(r'service call #\d+ \(nan, 0, 0\) m from .*: rejected', mark)
        return 'joint2 from joint_states' in logged.string

    wait_until(arrived, what='the partial joint state')
    assert lone_node.has(r'rad \[joint1, joint3, joint4, joint5 from start_positions; joint2 '
                         r'from joint_states\]: rejected')


def test_planned_paths_are_published_for_goals_and_calls(lone_node, peer) -> None:
    ns = '/planned_paths_are_published_for_goals_and_calls'
    paths = peer.inbox(Path, f'{ns}/planned_path')
    peer.publish(Point, f'{ns}/goal', Point(x=0.1, y=0.1, z=0.2))
    assert ends_at(paths.get(timeout=LIVENESS_S), (0.1, 0.1, 0.2))
    answer = peer.call(GetPlan, f'{ns}/plan_trajectory', plan_request((0.2, 0.0, 0.1)))
    published = paths.get(timeout=LIVENESS_S)
    assert ends_at(published, (0.2, 0.0, 0.1))
    assert len(published.poses) == len(answer.plan.poses)


def test_a_plan_past_max_planning_time_ends_timed_out(start_node, peer) -> None:
    node = start_node('-r', '__ns:=/deadline', '-p', 'algorithm:=pso', '-p', 'population:=5000',
                      '-p', 'max_iterations:=1000000', '-p', 'max_planning_time:=0.05')
    try:
        answer = peer.call(GetPlan, '/deadline/plan_trajectory', plan_request(HOPELESS_GOAL))
        assert list(answer.plan.poses) == []
        node.wait_for(r'service call #1 .*: timed_out: planning ran past max_planning_time '
                      r'0.05 s; best position error \S+ m')
        assert not node.has(r'published ')
    finally:
        assert node.stop() == 0, node.output


def test_malformed_messages_change_nothing(lone_node, peer) -> None:
    ns = '/malformed_messages_change_nothing'
    odd = [float('nan'), float('inf'), -float('inf'), 1e308, -1e308, 5e-324]
    peer.publish(Point, f'{ns}/goal', *(Point(x=value, y=0.1, z=odd[k - 1])
                                        for k, value in enumerate(odd)))
    peer.publish(JointState, f'{ns}/joint_states',
                 *(JointState(name=['joint1', 'joint2', 'joint2'], position=[value] * (k % 4))
                   for k, value in enumerate(odd)))
    answer = peer.call(GetPlan, f'{ns}/plan_trajectory', plan_request(tuple(PAPER_TARGET)))
    assert ends_at(answer.plan, tuple(PAPER_TARGET))
    # from q = 0 still (no message was taken), so the paper's exact minimum
    lone_node.wait_for(r'service call #1 .* from q = \(0, 0, 0, 0, 0\) rad: reached in 4.5143 s')
    assert 'Traceback' not in lone_node.output and lone_node.proc.poll() is None
