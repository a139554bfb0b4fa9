# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
A MoveIt client's side of plan_kinematic_path, run as a process with moveit_msgs loadable.

``python moveit_client.py SERVICE JSON``: JSON is a list of requests, each a dict of
``motion_request``'s keywords; prints one JSON line per answer (``answer_of``). The test
process itself has no moveit_msgs (it is built beside, with its own library path).
"""
from __future__ import annotations

import json
import sys
from typing import Any

from geometry_msgs.msg import Pose
from moveit_msgs.msg import (BoundingVolume, Constraints, JointConstraint,
                             MotionPlanRequest, MoveItErrorCodes, OrientationConstraint,
                             PositionConstraint)
from moveit_msgs.srv import GetMotionPlan
import rclpy
from shape_msgs.msg import SolidPrimitive

CODES = {getattr(MoveItErrorCodes, n): n for n in dir(MoveItErrorCodes)
         if n.isupper() and isinstance(getattr(MoveItErrorCodes, n), int)}


def motion_request(position: list[float], radius: float = 0.001, frame: str = '',
                   box: list[float] | None = None, link: str = '',
                   orientation: list[float] | None = None,
                   tolerances: tuple[float, float, float] = (0.001, 0.001, 0.001),
                   start: dict[str, float] | None = None, group: str = 'arm',
                   goals: int = 1, path_constraint: bool = False,
                   joint_goal: bool = False, velocity_scaling: float = 0.0,
                   planning_time: float = 5.0) -> MotionPlanRequest:
    """Build a request as pymoveit2's template does: a sphere (or box) and an orientation."""
    region = BoundingVolume()
    shape = (SolidPrimitive(type=SolidPrimitive.BOX, dimensions=box) if box is not None
             else SolidPrimitive(type=SolidPrimitive.SPHERE, dimensions=[radius]))
    pose = Pose()
    pose.position.x, pose.position.y, pose.position.z = position
    region.primitives, region.primitive_poses = [shape], [pose]
    where = PositionConstraint(link_name=link, constraint_region=region, weight=1.0)
    where.header.frame_id = frame
    goal = Constraints(position_constraints=[where])
    if orientation is not None:
        turn = OrientationConstraint(link_name=link, weight=1.0,
                                     absolute_x_axis_tolerance=tolerances[0],
                                     absolute_y_axis_tolerance=tolerances[1],
                                     absolute_z_axis_tolerance=tolerances[2])
        turn.header.frame_id = frame
        o = turn.orientation
        o.x, o.y, o.z, o.w = orientation
        goal.orientation_constraints = [turn]
    if joint_goal:
        goal.joint_constraints = [JointConstraint(joint_name='joint1', position=0.3)]
    request = MotionPlanRequest(group_name=group, goal_constraints=[goal] * goals,
                                allowed_planning_time=planning_time, planner_id='RRTConnect',
                                max_velocity_scaling_factor=velocity_scaling,
                                max_acceleration_scaling_factor=0.0)
    if start:
        request.start_state.joint_state.name = list(start)
        request.start_state.joint_state.position = [float(q) for q in start.values()]
    if path_constraint:
        request.path_constraints.position_constraints = [where]
    return request


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
