# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
A MoveIt client's side of plan_kinematic_path, run as a process with moveit_msgs loadable.

``python moveit_client.py SERVICE JSON``: JSON is a list of requests, each a dict of
``tools.moveit_requests.motion_request``'s keywords, and ``execute``: ``run``, ``cancel``
(once accepted), ``stop`` (``stop`` on trajectory_execution_event once it executes) or
``foreign`` (a joint renamed) sends the planned trajectory to execute_trajectory; or ``move``:
``plan_only`` or ``run`` sends the request as a move_action goal instead. Prints one JSON
line per answer (``answer_of``, and the execution's end; for move_action its result, status
and feedback states). The test process itself has no moveit_msgs (it is built beside, with
its own library path).
"""
from __future__ import annotations

import json
import sys
import threading
import time
from typing import Any, Callable


from moveit_msgs.action import ExecuteTrajectory, MoveGroup
from moveit_msgs.msg import MoveItErrorCodes
from moveit_msgs.srv import GetMotionPlan
import rclpy
from rclpy.action import ActionClient
from std_msgs.msg import String
from trajplan_ros.tools.moveit_requests import motion_request

CODES = {getattr(MoveItErrorCodes, n): n for n in dir(MoveItErrorCodes)
         if n.isupper() and isinstance(getattr(MoveItErrorCodes, n), int)}


def answer_of(r: Any) -> dict[str, Any]:
    """Return what a test reads of a MotionPlanResponse (or a MoveGroup result)."""
    planned = r.trajectory if hasattr(r, 'trajectory') else r.planned_trajectory
    traj = planned.joint_trajectory
    return {
        'code': CODES.get(r.error_code.val, r.error_code.val), 'message': r.error_code.message,
        'source': r.error_code.source, 'group': getattr(r, 'group_name', ''),
        'frame': traj.header.frame_id,
        'joint_names': list(traj.joint_names), 'planning_time': r.planning_time,
        'times': [p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec
                  for p in traj.points],
        'positions': [list(p.positions) for p in traj.points],
        'start_names': list(r.trajectory_start.joint_state.name),
        'start': list(r.trajectory_start.joint_state.position),
    }


def done(node: Any, future: Any) -> Any:
    """Return a future's result, spinning ``node`` up to 60 s for it."""
    rclpy.spin_until_future_complete(node, future, timeout_sec=60.0)
    if not future.done():
        raise SystemExit('no answer within 60 s')
    return future.result()


def spin_until(node: Any, ready: Callable[[], bool]) -> None:
    """Spin ``node`` until ``ready()``, up to 60 s."""
    deadline = time.monotonic() + 60.0
    while not ready():
        if time.monotonic() > deadline:
            raise SystemExit('waited 60 s in vain')
        rclpy.spin_once(node, timeout_sec=0.1)


def execute(node: Any, client: Any, trajectory: Any, how: str,
            events: Any) -> dict[str, Any]:
    """Send an ExecuteTrajectory goal (cancelled or stopped once executing); its end."""
    if not client.wait_for_server(timeout_sec=30.0):
        raise SystemExit('no execute_trajectory server within 30 s')
    goal = ExecuteTrajectory.Goal()
    goal.trajectory.joint_trajectory = trajectory
    monitored = threading.Event()
    handle = done(node, client.send_goal_async(goal,
                                               feedback_callback=lambda _: monitored.set()))
    if how == 'cancel' and handle.accepted:
        done(node, handle.cancel_goal_async())
    if how == 'stop' and handle.accepted:
        spin_until(node, monitored.is_set)             # executing: feedback MONITOR came
        spin_until(node, lambda: events.get_subscription_count() > 0)
        events.publish(String(data='stop'))
    result = done(node, handle.get_result_async())
    code = result.result.error_code
    return {'status': result.status, 'code': CODES.get(code.val, code.val),
            'message': code.message}


def move(node: Any, client: Any, request: Any, plan_only: bool) -> dict[str, Any]:
    """Send a MoveGroup goal; return its result's answer, status and feedback states."""
    if not client.wait_for_server(timeout_sec=30.0):
        raise SystemExit('no move_action server within 30 s')
    goal = MoveGroup.Goal(request=request)
    goal.planning_options.plan_only = plan_only
    states: list[str] = []
    handle = done(node, client.send_goal_async(
        goal, feedback_callback=lambda f: states.append(f.feedback.state)))
    result = done(node, handle.get_result_async())
    answer = answer_of(result.result)
    answer.update(status=result.status, states=states,
                  executed=len(result.result.executed_trajectory.joint_trajectory.points))
    return answer


def main() -> None:
    service, specs = sys.argv[1], json.loads(sys.argv[2])
    rclpy.init()
    node = rclpy.create_node('moveit_test_client')
    client = node.create_client(GetMotionPlan, service)
    namespace = service.rsplit('/', 1)[0]
    executor = ActionClient(node, ExecuteTrajectory, f'{namespace}/execute_trajectory')
    mover = ActionClient(node, MoveGroup, f'{namespace}/move_action')
    events = node.create_publisher(String, f'{namespace}/trajectory_execution_event', 10)
    if not client.wait_for_service(timeout_sec=30.0):
        raise SystemExit(f'no service {service} within 30 s')
    for spec in specs:
        run, moved = spec.pop('execute', None), spec.pop('move', None)
        if moved is not None:
            answer = move(node, mover, motion_request(**spec), moved == 'plan_only')
            print(json.dumps(answer), flush=True)
            continue
        response = done(node, client.call_async(GetMotionPlan.Request(
            motion_plan_request=motion_request(**spec)))).motion_plan_response
        answer = answer_of(response)
        if run is not None:
            trajectory = response.trajectory.joint_trajectory
            if run == 'foreign':
                trajectory.joint_names = ['a'] + list(trajectory.joint_names[1:])
            answer['execution'] = execute(node, executor, trajectory, run, events)
        print(json.dumps(answer), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == '__main__':
    main()
