# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Execution through a FollowJointTrajectory server, over real DDS.

The node (``execution: action``) and the package's demo_controller run as processes with the
control_msgs the session fixture provides; the test process sees them through plan_results,
``trajplan call --wait-execution``'s code and the controller's log, its account of the goals it
executes (the action's status topic keeps only its newest array: a reader may miss some).
Without control_msgs
(and no sources to build it) these tests skip with the reason, except the refusal of the
parameter, which needs its absence.
"""
from __future__ import annotations

import itertools
import queue
import re
import signal
from typing import Callable, Iterator

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Point
from nav_msgs.srv import GetPlan
from node_under_test import LIVENESS_S, NodeProcess
import pytest
from rclpy.parameter import Parameter
from trajectory_msgs.msg import JointTrajectory
from trajplan_ros.ros import outcomes
from trajplan_ros.tools.node_commands import call_planner
from trajplan_ros.tools.node_process import wait_until
from trajplan_ros.tools.ros_client import plan_request, RosClient

pytestmark = pytest.mark.dds

NS = '/exec'
GOALS = ((0.151171, 0.19162, 0.172124), (0.2, 0.1, 0.15))
#: The controller's ``fail`` -> the status its goal ends in, and what the controller says.
RESULTS = {
    '': ('executed', 'reached the goal'),
    'reject': ('rejected', 'the controller rejected the goal'),
    'invalid_goal': ('invalid_goal', 'controller: the goal is invalid'),
    'invalid_joints': ('invalid_joints', "controller: the goal's joints do not match"),
    'old_header_timestamp': ('old_header_timestamp', "controller: the goal's header.stamp"),
    'path_tolerance': ('path_tolerance_violated',
                       'controller: Aborted due to path tolerance violation'),
    'goal_tolerance': ('goal_tolerance_violated',
                       'controller: Aborted due to goal tolerance violation'),
    'stall': ('timed_out', 'the controller had not finished 0.5 s after the motion'),
}


def start_controller(start_node: Callable[..., NodeProcess], env: dict[str, str],
                     namespace: str, *params: str) -> NodeProcess:
    """Run the package's demo_controller in ``namespace`` and wait until it serves."""
    controller = start_node('-r', f'__ns:={namespace}', *params, ready=False, env=env,
                            executable='demo_controller')
    controller.wait_for(r'demo_controller\]: ready: ')
    return controller


@pytest.fixture(scope='module')
def loop(start_node: Callable[..., NodeProcess],
         control_msgs_env: dict[str, str]) -> Iterator[tuple[NodeProcess, NodeProcess]]:
    """Run the node executing through the action, and the demo controller it talks to."""
    controller = start_controller(start_node, control_msgs_env, NS, '-p', 'fail_after:=0.1')
    node = start_node('-r', f'__ns:={NS}', '-p', 'execution:=action', '-p',
                      'angular_velocity:=1.0', '-p', 'controller_timeout:=3.0',
                      env=control_msgs_env)
    yield node, controller
    assert node.stop() == 0, node.output
    assert controller.stop() == 0, controller.output


def action_clients(peer: RosClient, namespace: str) -> list[str]:
    """Return the action clients the graph lists for the node ``trajplan`` in ``namespace``."""
    from rclpy.action import get_action_client_names_and_types_by_node

    found: list[str] = []

    def listed() -> bool:
        found[:] = [name for name, _ in get_action_client_names_and_types_by_node(
            peer.node, 'trajplan', namespace)]
        return bool(found)

    wait_until(listed, LIVENESS_S, f'the action client of {namespace}/trajplan in the graph')
    return found


#: Where the controller is (its namespace, and how its joint_states reach the node's), and how
#: the node is told: by a remapping rule, by controller_action, by a name in its namespace.
ELSEWHERE = {
    'remap': ('/by_remap', '/by_remap/arm_controller',
              ('-r', 'follow_joint_trajectory:=/by_remap/arm_controller/follow_joint_trajectory')),
    'parameter': ('/by_param', '/by_param/arm_controller',
                  ('-p', 'controller_action:=/by_param/arm_controller/follow_joint_trajectory')),
    'namespace': ('/arm1', '/arm1/arm_controller',
                  ('-p', 'controller_action:=arm_controller/follow_joint_trajectory')),
}


@pytest.mark.parametrize('how', list(ELSEWHERE))
def test_a_controller_under_its_own_name_is_reached(
        start_node: Callable[..., NodeProcess], control_msgs_env: dict[str, str],
        peer: RosClient, how: str, capsys: pytest.CaptureFixture[str]) -> None:
    namespace, controller_namespace, told = ELSEWHERE[how]
    # the controller's own name comes from its namespace alone, as joint_trajectory_controller's
    controller = start_controller(start_node, control_msgs_env, controller_namespace, '-r',
                                  f'joint_states:={namespace}/joint_states')
    assert controller.has(rf'ready: {controller_namespace}/follow_joint_trajectory, ')
    node = start_node('-r', f'__ns:={namespace}', '-p', 'execution:=action', '-p',
                      'angular_velocity:=1.0', *told, env=control_msgs_env)
    code = call_planner(peer, GOALS[1], service=f'{namespace}/plan_trajectory', tolerance=0.0,
                        timeout=LIVENESS_S, trajectory_topic=None, wait_execution=True)
    out, err = capsys.readouterr()
    assert code == 0 and 'executed: reached the goal' in out, err
    assert action_clients(peer, namespace) == [f'{controller_namespace}/follow_joint_trajectory']
    assert node.stop() == 0, node.output
    assert controller.stop() == 0, controller.output


def test_a_missing_controller_is_named_as_the_client_names_it(
        start_node: Callable[..., NodeProcess], control_msgs_env: dict[str, str],
        peer: RosClient) -> None:
    namespace = '/exec_missing'
    node = start_node('-r', f'__ns:={namespace}', '-r',
                      'follow_joint_trajectory:=/elsewhere/follow_joint_trajectory', '-p',
                      'execution:=action', '-p', 'controller_timeout:=0.5', '-p',
                      'start_tolerance:=0.0', env=control_msgs_env)
    results = peer.inbox(DiagnosticStatus, f'{namespace}/plan_results', qos=outcomes.QOS)
    assert peer.call(GetPlan, f'{namespace}/plan_trajectory', plan_request(GOALS[0])).plan.poses
    (status, message), = execution_statuses(results, 'service call #1')
    named = re.match(r'no FollowJointTrajectory server on (\S+) within 0.5 s', message)
    assert status == 'no_controller' and named, message
    assert action_clients(peer, namespace) == [named.group(1)] == [
        '/elsewhere/follow_joint_trajectory']
    refused, = peer.set_parameters(f'{namespace}/trajplan', [Parameter('controller_action',
                                                                       value='arm controller')])
    assert not refused.successful
    assert refused.reason.startswith("'arm controller' is not a valid action name: failed to "
                                     'resolve name: topic name must not contain characters '
                                     'other than alphanumerics'), refused.reason
    assert node.stop() == 0, node.output


def fail(peer: RosClient, namespace: str, how: str) -> None:
    """Tell the demo controller in ``namespace`` how to end the next goals."""
    result, = peer.set_parameters(f'{namespace}/demo_controller',
                                  [Parameter('fail', value=how)])
    assert result.successful, result.reason


def execution_statuses(box: queue.Queue, label: str) -> list[tuple[str, str]]:
    """Return (status, message) of the execution of the job ``label`` up to its end."""
    seen = []
    while not seen or seen[-1][0] not in outcomes.TERMINAL:
        msg = box.get(timeout=LIVENESS_S)
        values = outcomes.outcome_values(msg)
        if msg.name.endswith(f': {label}') and values['stage'] == 'execution':
            seen.append((values['status'], msg.message))
    return seen


@pytest.mark.parametrize('how', list(RESULTS))
def test_every_result_reaches_plan_results_and_the_call(
        loop: tuple[NodeProcess, NodeProcess], peer: RosClient, how: str,
        capsys: pytest.CaptureFixture[str]) -> None:
    fail(peer, NS, how)
    status, said = RESULTS[how]
    timeout = 0.5 if how == 'stall' else 3.0     # the first plan waits for joint_states
    result, = peer.set_parameters(f'{NS}/trajplan', [Parameter('controller_timeout',
                                                               value=timeout)])
    assert result.successful, result.reason
    code = call_planner(peer, GOALS[list(RESULTS).index(how) % 2],
                        service=f'{NS}/plan_trajectory', tolerance=0.0, timeout=LIVENESS_S,
                        trajectory_topic=None, wait_execution=True)
    out, err = capsys.readouterr()
    if how:
        assert code == 1, out
        assert f'trajplan: not executed: {status}: ' in err and said in err, err
    else:
        assert code == 0, err
        assert 'execution: accepted' in out
        # the joint error as measured from the controller's joint_states after its result
        error = re.search(r'^executed: reached the goal \((\S+) rad from the goal on joint ',
                          out, re.M)
        assert error and float(error.group(1)) < 0.02, out


def test_a_newer_goal_preempts_leaving_one_goal_executing(
        loop: tuple[NodeProcess, NodeProcess], peer: RosClient) -> None:
    node, controller = loop
    results = peer.inbox(DiagnosticStatus, f'{NS}/plan_results', qos=outcomes.QOS)
    fail(peer, NS, 'stall')                       # the first motion executes until preempted
    result, = peer.set_parameters(f'{NS}/trajplan', [Parameter('controller_timeout',
                                                               value=LIVENESS_S)])
    assert result.successful, result.reason
    mark, since = node.mark(), controller.mark()
    peer.publish(Point, f'{NS}/goal', Point(x=GOALS[0][0], y=GOALS[0][1], z=GOALS[0][2]))
    first = node.wait_for(r'\]: (goal #\d+) .*: execution: accepted', mark).group(1)
    fail(peer, NS, '')
    mark = node.mark()
    peer.publish(Point, f'{NS}/goal', Point(x=GOALS[1][0], y=GOALS[1][1], z=GOALS[1][2]))
    second = node.wait_for(r'\]: (goal #\d+) .*: execution: accepted', mark).group(1)
    status, message = execution_statuses(results, first)[-1]
    assert status == 'preempted' and message.startswith(f'cancelled for {second} ('), message
    ends = dict(execution_statuses(results, second))
    assert ends['executed'].startswith('reached the goal')
    # the controller's own account: never two goals executing, none once the second ended
    controller.wait_for(r'goal ended: succeed', since)         # its log comes through a pipe
    events = [line for line in controller.lines[since:] if 'goal accepted' in line
              or 'goal ended' in line]
    events = events[next(i for i, line in enumerate(events) if 'accepted' in line):]  # ours
    executing = list(itertools.accumulate(1 if 'accepted' in line else -1 for line in events))
    assert executing == [1, 0, 1, 0], events


def test_ctrl_c_cancels_the_executing_goal_and_a_missing_controller_is_reported(
        start_node: Callable[..., NodeProcess], control_msgs_env: dict[str, str],
        peer: RosClient) -> None:
    namespace = '/exec_stop'
    node = start_node('-r', f'__ns:={namespace}', '-p', 'execution:=action', '-p',
                      'controller_timeout:=0.5', env=control_msgs_env)
    results = peer.inbox(DiagnosticStatus, f'{namespace}/plan_results', qos=outcomes.QOS)
    assert peer.call(GetPlan, f'{namespace}/plan_trajectory', plan_request(GOALS[0])).plan.poses
    (status, message), = execution_statuses(results, 'service call #1')
    assert status == 'no_controller', message
    assert f'no FollowJointTrajectory server on {namespace}/follow_joint_trajectory within ' \
           '0.5 s' in message
    controller = start_controller(start_node, control_msgs_env, namespace, '-p', 'fail:=stall')
    result, = peer.set_parameters(f'{namespace}/trajplan', [Parameter('controller_timeout',
                                                                      value=LIVENESS_S)])
    assert result.successful, result.reason
    mark = node.mark()
    assert peer.call(GetPlan, f'{namespace}/plan_trajectory', plan_request(GOALS[1])).plan.poses
    node.wait_for(r'service call #2 .*: execution: accepted', mark)
    since = controller.mark()
    assert node.stop(signal.SIGINT) == 0, node.output
    status, message = execution_statuses(results, 'service call #2')[-1]
    assert status == 'shut_down' and message.startswith('cancelled at shutdown ('), message
    # the controller's own account: the goal it executed (it never moves: stall) was cancelled
    controller.wait_for(r'goal ended: canceled, error_code 0: cancelled on request', since)
    assert controller.stop() == 0, controller.output


def test_without_control_msgs_action_is_refused_and_none_sends_nothing(
        start_node: Callable[..., NodeProcess], ros_env: dict[str, str],
        peer: RosClient) -> None:
    namespace = '/exec_plain'
    node = start_node('-r', f'__ns:={namespace}', env=ros_env)
    result, = peer.set_parameters(f'{namespace}/trajplan', [Parameter('execution',
                                                                      value='none')])
    assert result.successful, result.reason
    trajectories = peer.inbox(JointTrajectory, f'{namespace}/joint_trajectory')
    results = peer.inbox(DiagnosticStatus, f'{namespace}/plan_results', qos=outcomes.QOS)
    assert peer.call(GetPlan, f'{namespace}/plan_trajectory', plan_request(GOALS[0])).plan.poses
    node.wait_for(r'service call #1 .* not sent \(execution none\)')
    values = outcomes.outcome_values(results.get(timeout=LIVENESS_S))
    assert (values['status'], values['stage']) == ('succeeded', 'plan')
    assert trajectories.empty()
    refused, = peer.set_parameters(f'{namespace}/trajplan', [Parameter('execution',
                                                                       value='action')])
    if refused.successful:
        pytest.skip('control_msgs loads in the test environment: nothing to refuse')
    assert 'execution action needs control_msgs' in refused.reason
    assert 'sudo apt install ros-jazzy-control-msgs' in refused.reason
    assert node.stop() == 0, node.output
    bad = start_node('-r', f'__ns:={namespace}', '-p', 'execution:=action', ready=False,
                     env=ros_env)
    assert bad.proc.wait(timeout=LIVENESS_S) == 2
    assert bad.has(r'invalid parameters: execution action needs control_msgs'), bad.output
