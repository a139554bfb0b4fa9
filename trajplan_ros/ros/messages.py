# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Conversion between the planning core's results and ROS messages, as pure functions."""
from __future__ import annotations

import array

from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path
import numpy as np
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from trajplan_ros.kinematics import ArmModel
from trajplan_ros.planning import Trajectory


__all__ = ['path_msg', 'quaternions', 'trajectory_msg']


def quaternions(rot: np.ndarray) -> np.ndarray:
    """
    Convert rotation matrices (N, 3, 3) to unit quaternions, (N, 4) as x, y, z, w.

    Builds K = 4 q q^T (q = (w, x, y, z)) from the matrix entries and takes the row of its
    largest diagonal entry, which is well conditioned for every rotation.
    """
    m00, m11, m22 = rot[:, 0, 0], rot[:, 1, 1], rot[:, 2, 2]
    wx, wy, wz = (rot[:, 2, 1] - rot[:, 1, 2], rot[:, 0, 2] - rot[:, 2, 0],
                  rot[:, 1, 0] - rot[:, 0, 1])
    xy, xz, yz = (rot[:, 0, 1] + rot[:, 1, 0], rot[:, 0, 2] + rot[:, 2, 0],
                  rot[:, 1, 2] + rot[:, 2, 1])
    k = np.stack([
        np.stack([1 + m00 + m11 + m22, wx, wy, wz], axis=-1),
        np.stack([wx, 1 + m00 - m11 - m22, xy, xz], axis=-1),
        np.stack([wy, xy, 1 - m00 + m11 - m22, yz], axis=-1),
        np.stack([wz, xz, yz, 1 - m00 - m11 + m22], axis=-1)], axis=1)
    rows = np.arange(rot.shape[0])
    best = np.argmax(np.diagonal(k, axis1=1, axis2=2), axis=1)
    q = k[rows, best] / (2.0 * np.sqrt(k[rows, best, best]))[:, None]
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)          # w >= 0: one of the two equal quaternions
    return q[:, [1, 2, 3, 0]]


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
