# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
A MoveIt client's side of plan_kinematic_path, run as a process with moveit_msgs loadable.

``python moveit_client.py SERVICE JSON``: JSON is a list of requests, each a dict of
``tools.moveit_requests.motion_request``'s keywords, and ``execute``: ``run``, ``cancel``
(once accepted) or ``foreign`` (a joint renamed) sends the planned trajectory to
execute_trajectory; prints one JSON line per answer (``answer_of``, and the execution's
end). The test process itself has no moveit_msgs (it is built beside, with its own library
path).
"""
from __future__ import annotations

import json
import sys
from typing import Any

from moveit_msgs.action import ExecuteTrajectory
from moveit_msgs.msg import MoveItErrorCodes
from moveit_msgs.srv import GetMotionPlan
import rclpy
from rclpy.action import ActionClient
from trajplan_ros.tools.moveit_requests import motion_request

CODES = {getattr(MoveItErrorCodes, n): n for n in dir(MoveItErrorCodes)
         if n.isupper() and isinstance(getattr(MoveItErrorCodes, n), int)}


def answer_of(response: Any) -> dict[str, Any]:
    """Return what a test reads of a MotionPlanResponse."""
    r = response.motion_plan_response
    traj = r.trajectory.joint_trajectory
    return {
        'code': CODES.get(r.error_code.val, r.error_code.val), 'message': r.error_code.message,
        'source': r.error_code.source, 'group': r.group_name, 'frame': traj.header.frame_id,
        'joint_names': list(traj.joint_names), 'planning_time': r.planning_time,
        'times': [p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec
                  for p in traj.points],
        'positions': [list(p.positions) for p in traj.points],
        'start_names': list(r.trajectory_start.joint_state.name),
        'start': list(r.trajectory_start.joint_state.position),
    }


def execute(node: Any, client: Any, trajectory: Any, cancel: bool) -> dict[str, Any]:
    """Send an ExecuteTrajectory goal (cancelled once accepted, with ``cancel``); its end."""
    def done(future: Any) -> Any:
        rclpy.spin_until_future_complete(node, future, timeout_sec=60.0)
        if not future.done():
            raise SystemExit('no answer within 60 s from execute_trajectory')
        return future.result()

    if not client.wait_for_server(timeout_sec=30.0):
        raise SystemExit('no execute_trajectory server within 30 s')
    goal = ExecuteTrajectory.Goal()
    goal.trajectory.joint_trajectory = trajectory
    handle = done(client.send_goal_async(goal))
    if cancel and handle.accepted:
        done(handle.cancel_goal_async())
    result = done(handle.get_result_async())
    code = result.result.error_code
    return {'status': result.status, 'code': CODES.get(code.val, code.val),
            'message': code.message}


def main() -> None:
    service, specs = sys.argv[1], json.loads(sys.argv[2])
    rclpy.init()
    node = rclpy.create_node('moveit_test_client')
    client = node.create_client(GetMotionPlan, service)
    executor = ActionClient(node, ExecuteTrajectory,
                            service.rsplit('/', 1)[0] + '/execute_trajectory')
    if not client.wait_for_service(timeout_sec=30.0):
        raise SystemExit(f'no service {service} within 30 s')
    for spec in specs:
        run = spec.pop('execute', None)
        future = client.call_async(GetMotionPlan.Request(
            motion_plan_request=motion_request(**spec)))
        rclpy.spin_until_future_complete(node, future, timeout_sec=60.0)
        if not future.done():
            raise SystemExit(f'no answer within 60 s to {spec}')
        answer = answer_of(future.result())
        if run is not None:
            trajectory = future.result().motion_plan_response.trajectory.joint_trajectory
            if run == 'foreign':
                trajectory.joint_names = ['a'] + list(trajectory.joint_names[1:])
            answer['execution'] = execute(node, executor, trajectory, run == 'cancel')
        print(json.dumps(answer), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == '__main__':
    main()
