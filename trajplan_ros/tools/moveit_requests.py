# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
MotionPlanRequests as MoveIt's clients build them, for the tests and the bench.

moveit_msgs is imported when a request is built: it is not on PyPI (``ros.moveit_interfaces``).

``motion_request`` follows pymoveit2's template: one goal region (a sphere, or a box) on a link,
optionally an orientation with its three tolerances, a start state by joint name.
"""
from __future__ import annotations

from typing import Any

__all__ = ['motion_request']


def motion_request(position: list[float] | None = None, radius: float = 0.001, frame: str = '',
                   box: list[float] | None = None, link: str = '',
                   orientation: list[float] | None = None,
                   tolerances: tuple[float, float, float] = (0.001, 0.001, 0.001),
                   start: dict[str, float] | None = None, group: str = 'arm',
                   regions: list[list[float]] | None = None, path_constraint: bool = False,
                   joint_goal: dict[str, float] | None = None, velocity_scaling: float = 0.0,
                   planning_time: float = 5.0) -> Any:
    """
    Build a request as pymoveit2's template does: a sphere (or box) and an orientation.

    ``joint_goal``: JointConstraints (0.001 rad either side), beside the region if a
    ``position`` is given too. ``regions``: more goal regions, spheres of ``radius`` there.
    """
    from moveit_msgs.msg import (Constraints, JointConstraint, MotionPlanRequest,
                                 OrientationConstraint)

    where = _region(position or [0.0, 0.0, 0.0], radius, box, link, frame)
    goal = Constraints(position_constraints=[where] if position is not None else [])
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
        goal.joint_constraints = [JointConstraint(joint_name=name, position=float(angle),
                                                  tolerance_above=0.001,
                                                  tolerance_below=0.001, weight=1.0)
                                  for name, angle in joint_goal.items()]
    more = [Constraints(position_constraints=[_region(c, radius, None, link, frame)])
            for c in regions or []]
    request = MotionPlanRequest(group_name=group, goal_constraints=[goal, *more],
                                allowed_planning_time=planning_time, planner_id='RRTConnect',
                                max_velocity_scaling_factor=velocity_scaling,
                                max_acceleration_scaling_factor=0.0)
    if start:
        request.start_state.joint_state.name = list(start)
        request.start_state.joint_state.position = [float(q) for q in start.values()]
    if path_constraint:
        request.path_constraints.position_constraints = [where]
    return request


def _region(centre: list[float], radius: float, box: list[float] | None, link: str,
            frame: str) -> Any:
    """Return a PositionConstraint on ``link``: a sphere of ``radius`` (or a box) at centre."""
    from geometry_msgs.msg import Pose
    from moveit_msgs.msg import BoundingVolume, PositionConstraint
    from shape_msgs.msg import SolidPrimitive

    shape = (SolidPrimitive(type=SolidPrimitive.BOX, dimensions=box) if box is not None
             else SolidPrimitive(type=SolidPrimitive.SPHERE, dimensions=[radius]))
    pose = Pose()
    pose.position.x, pose.position.y, pose.position.z = centre
    where = PositionConstraint(link_name=link, weight=1.0, constraint_region=BoundingVolume(
        primitives=[shape], primitive_poses=[pose]))
    where.header.frame_id = frame
    return where
