# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Conversion between the planning core's results and ROS messages, as pure functions."""
from __future__ import annotations

import array

from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from nav_msgs.msg import Path
import numpy as np
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from trajplan_ros.collision.scene import pose_matrix
from trajplan_ros.kinematics import ArmModel
from trajplan_ros.kinematics.rotations import quaternions
from trajplan_ros.planning import Trajectory


__all__ = ['path_msg', 'pose_matrix_of', 'pose_msg', 'trajectory_msg']


def trajectory_msg(traj: Trajectory) -> JointTrajectory:
    """
    Build the JointTrajectory of ``traj``; header.stamp stays zero ("start now").

    Each point carries the fields ``traj`` carries (servo points: positions only).
    """
    msg = JointTrajectory(joint_names=list(traj.joint_names))
    rows = len(traj.times)
    velocities = traj.velocities if traj.velocities is not None else [()] * rows
    accelerations = traj.accelerations if traj.accelerations is not None else [()] * rows
    points = []
    for ns, q, v, a in zip(traj.nanoseconds, traj.positions, velocities, accelerations):
        point = JointTrajectoryPoint(positions=array.array('d', q),
                                     velocities=array.array('d', v),
                                     accelerations=array.array('d', a))
        point.time_from_start.sec, point.time_from_start.nanosec = divmod(ns, 1_000_000_000)
        points.append(point)
    msg.points = points
    return msg


def path_msg(arm: ArmModel, traj: Trajectory, header: Header) -> Path:
    """Build the tool path of ``traj``: one pose per trajectory point (forward kinematics)."""
    tool = arm.frames(traj.positions)[:, -1]
    quats = quaternions(tool[:, :3, :3])
    poses = []
    for (px, py, pz), (qx, qy, qz, qw) in zip(tool[:, :3, 3].tolist(), quats.tolist()):
        pose = PoseStamped(header=header)
        p, o = pose.pose.position, pose.pose.orientation
        p.x, p.y, p.z = px, py, pz
        o.x, o.y, o.z, o.w = qx, qy, qz, qw
        poses.append(pose)
    return Path(header=header, poses=poses)


def pose_msg(matrix: np.ndarray) -> Pose:
    """Return a 4x4 transform as a geometry_msgs/Pose."""
    x, y, z, w = (float(v) for v in quaternions(matrix[None, :3, :3])[0])
    t = matrix[:3, 3]
    return Pose(position=Point(x=float(t[0]), y=float(t[1]), z=float(t[2])),
                orientation=Quaternion(x=x, y=y, z=z, w=w))


def pose_matrix_of(pose: Pose, where: str) -> np.ndarray:
    """
    Return a geometry_msgs/Pose as 4x4 (InvalidCollisionInput: not a pose; ``where`` names it).

    A zero quaternion, a message's default as RViz and MoveIt's clients leave it, is no rotation.
    """
    p, o = pose.position, pose.orientation
    q = (o.x, o.y, o.z, o.w) if (o.x, o.y, o.z, o.w) != (0, 0, 0, 0) else (0, 0, 0, 1)
    return pose_matrix((p.x, p.y, p.z), q, where)
