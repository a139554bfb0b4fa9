# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
A MoveIt client's side of plan_kinematic_path, run as a process with moveit_msgs loadable.

``python moveit_client.py SERVICE JSON``: JSON is a list of requests, each a dict of
``tools.moveit_requests.motion_request``'s keywords; prints one JSON line per answer
(``answer_of``). The test process itself has no moveit_msgs (it is built beside, with its own
library path).
"""
from __future__ import annotations

import json
import sys
from typing import Any

from moveit_msgs.msg import MoveItErrorCodes
from moveit_msgs.srv import GetMotionPlan
import rclpy
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


def main() -> None:
    service, specs = sys.argv[1], json.loads(sys.argv[2])
    rclpy.init()
    node = rclpy.create_node('moveit_test_client')
    client = node.create_client(GetMotionPlan, service)
    if not client.wait_for_service(timeout_sec=30.0):
        raise SystemExit(f'no service {service} within 30 s')
    for spec in specs:
        future = client.call_async(GetMotionPlan.Request(
            motion_plan_request=motion_request(**spec)))
        rclpy.spin_until_future_complete(node, future, timeout_sec=60.0)
        if not future.done():
            raise SystemExit(f'no answer within 60 s to {spec}')
        print(json.dumps(answer_of(future.result())), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == '__main__':
    main()
