# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
A MoveIt client's side of the planning scene, run as a process with moveit_msgs loadable.

``python moveit_scene_client.py NAMESPACE JSON``: JSON is a list of steps, each one key:

* ``publish``: a CollisionObject on ``collision_object`` (``id``, ``operation`` ADD, REMOVE,
  APPEND or MOVE, ``frame``, ``pose`` [x, y, z], ``primitives`` [[TYPE, dimensions,
  [x, y, z]], ...], ``mesh`` [vertices, triangles]), then ``get_planning_scene`` until its
  objects are ``expect`` (ids); prints the ids.
* ``plan``: ``tools.moveit_requests.motion_request``'s keywords to plan_kinematic_path;
  prints the code, the message and the last point.
* ``apply``: an ApplyPlanningScene of ``objects`` (as ``publish``), ``is_diff``, ``acm``
  (a collision-matrix entry); prints whether it succeeded.
* ``scene``: prints get_planning_scene's objects (id, frame, primitive types, meshes) and
  robot state's joint names.
* ``fk``: compute_fk of ``links`` in ``frame`` at ``state`` (angles by name); prints the code
  and each pose as [x, y, z, qx, qy, qz, qw].
* ``ik``: compute_ik of the tip's ``position`` and ``orientation`` in ``frame`` from ``seed``
  (angles by name), ``avoid_collisions``; prints the code, message and solution by name.
"""
from __future__ import annotations

import json
import sys
import time
from typing import Any

from geometry_msgs.msg import Point, Pose
from moveit_msgs.msg import CollisionObject, MoveItErrorCodes
from moveit_msgs.srv import (ApplyPlanningScene, GetMotionPlan, GetPlanningScene,
                             GetPositionFK, GetPositionIK)
import rclpy
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from shape_msgs.msg import Mesh, MeshTriangle, SolidPrimitive
from trajplan_ros.tools.moveit_requests import motion_request

CODES = {getattr(MoveItErrorCodes, n): n for n in dir(MoveItErrorCodes)
         if n.isupper() and isinstance(getattr(MoveItErrorCodes, n), int)}


def pose(xyz: list[float]) -> Pose:
    out = Pose()
    out.position.x, out.position.y, out.position.z = xyz
    return out


def collision_object(spec: dict[str, Any]) -> CollisionObject:
    """Build a CollisionObject from a step's description."""
    out = CollisionObject(id=spec['id'], operation=getattr(CollisionObject,
                                                           spec.get('operation', 'ADD')))
    out.header.frame_id = spec.get('frame', '')
    out.pose = pose(spec.get('pose', [0.0, 0.0, 0.0]))
    for kind, dims, at in spec.get('primitives', []):
        out.primitives.append(SolidPrimitive(type=getattr(SolidPrimitive, kind),
                                             dimensions=dims))
        out.primitive_poses.append(pose(at))
    if 'mesh' in spec:
        vertices, triangles = spec['mesh']
        out.meshes.append(Mesh(vertices=[Point(x=x, y=y, z=z) for x, y, z in vertices],
                               triangles=[MeshTriangle(vertex_indices=t) for t in triangles]))
    return out


def call(node: Any, client: Any, request: Any) -> Any:
    """Return a service's answer to ``request`` (60 s at most)."""
    if not client.wait_for_service(timeout_sec=30.0):
        raise SystemExit(f'no service {client.srv_name} within 30 s')
    future = client.call_async(request)
    rclpy.spin_until_future_complete(node, future, timeout_sec=60.0)
    if not future.done():
        raise SystemExit(f'no answer within 60 s from {client.srv_name}')
    return future.result()


def pose_list(p: Pose) -> list[float]:
    return [p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y,
            p.orientation.z, p.orientation.w]


def solve(node: Any, client: Any, spec: dict[str, Any]) -> dict[str, Any]:
    """Ask compute_ik as a ``ik`` step says; return what the test reads of the answer."""
    request = GetPositionIK.Request()
    asked = request.ik_request
    asked.avoid_collisions = spec.get('avoid_collisions', True)
    asked.pose_stamped.header.frame_id = spec.get('frame', '')
    asked.pose_stamped.pose = pose(spec['position'])
    o = asked.pose_stamped.pose.orientation
    o.x, o.y, o.z, o.w = spec['orientation']
    state = asked.robot_state.joint_state
    state.name, state.position = zip(*spec['seed'].items())
    r = call(node, client, request)
    solution = r.solution.joint_state
    return {'code': CODES.get(r.error_code.val, r.error_code.val),
            'message': r.error_code.message,
            'solution': dict(zip(solution.name, solution.position))}


def main() -> None:
    namespace, steps = sys.argv[1], json.loads(sys.argv[2])
    rclpy.init()
    node = rclpy.create_node('moveit_scene_client')
    objects = node.create_publisher(
        CollisionObject, f'{namespace}/collision_object',
        QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE))
    scenes = node.create_client(GetPlanningScene, f'{namespace}/get_planning_scene')
    applies = node.create_client(ApplyPlanningScene, f'{namespace}/apply_planning_scene')
    plans = node.create_client(GetMotionPlan, f'{namespace}/plan_kinematic_path')
    fk = node.create_client(GetPositionFK, f'{namespace}/compute_fk')
    ik = node.create_client(GetPositionIK, f'{namespace}/compute_ik')

    def scene() -> Any:
        return call(node, scenes, GetPlanningScene.Request()).scene

    deadline = time.monotonic() + 30.0
    while objects.get_subscription_count() == 0 and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.1)
    for step in steps:
        if 'publish' in step:
            objects.publish(collision_object(step['publish']))
            deadline, ids = time.monotonic() + 30.0, None
            while ids != sorted(step['expect']) and time.monotonic() < deadline:
                ids = sorted(o.id for o in scene().world.collision_objects)
            print(json.dumps({'ids': ids}), flush=True)
        elif 'plan' in step:
            r = call(node, plans, GetMotionPlan.Request(
                motion_plan_request=motion_request(**step['plan']))).motion_plan_response
            points = r.trajectory.joint_trajectory.points
            print(json.dumps({'code': CODES.get(r.error_code.val, r.error_code.val),
                              'message': r.error_code.message,
                              'last': list(points[-1].positions) if points else None}),
                  flush=True)
        elif 'apply' in step:
            request = ApplyPlanningScene.Request()
            request.scene.is_diff = step['apply'].get('is_diff', True)
            request.scene.world.collision_objects = [
                collision_object(o) for o in step['apply'].get('objects', [])]
            if step['apply'].get('acm'):
                request.scene.allowed_collision_matrix.entry_names = ['link1', 'link3']
            print(json.dumps({'success': call(node, applies, request).success}), flush=True)
        elif 'fk' in step:
            request = GetPositionFK.Request(fk_link_names=step['fk']['links'])
            request.header.frame_id = step['fk'].get('frame', '')
            state = request.robot_state.joint_state
            state.name, state.position = zip(*step['fk']['state'].items())
            r = call(node, fk, request)
            print(json.dumps({'code': CODES.get(r.error_code.val, r.error_code.val),
                              'message': r.error_code.message,
                              'links': list(r.fk_link_names),
                              'poses': [pose_list(p.pose) for p in r.pose_stamped]}),
                  flush=True)
        elif 'ik' in step:
            print(json.dumps(solve(node, ik, step['ik'])), flush=True)
        else:
            got = scene()
            print(json.dumps({
                'objects': [{'id': o.id, 'frame': o.header.frame_id,
                             'primitives': [p.type for p in o.primitives],
                             'meshes': len(o.meshes)} for o in got.world.collision_objects],
                'joints': list(got.robot_state.joint_state.name)}), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == '__main__':
    main()
