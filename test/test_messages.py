# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Conversion of plans into ROS messages, as pure functions: no DDS, no node."""
import numpy as np
from std_msgs.msg import Header
from trajplan_ros import paper_arm, servo_trajectory
from trajplan_ros.kinematics.rotations import quaternions
from trajplan_ros.ros.messages import path_msg, trajectory_msg


ARM = paper_arm()


def matrix(q: np.ndarray) -> np.ndarray:
    """Return the rotation matrix of a unit quaternion (x, y, z, w)."""
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def test_quaternions_reproduce_their_rotations() -> None:
    rng = np.random.default_rng(5)
    q = rng.uniform(ARM.lower, ARM.upper, (200, ARM.n_joints))
    rot = ARM.frames(q)[:, -1, :3, :3]
    # the hard cases too: half turns about each axis (w = 0) and the identity
    rot = np.concatenate((rot, np.diag([1.0, -1, -1])[None], np.diag([-1.0, 1, -1])[None],
                          np.diag([-1.0, -1, 1])[None], np.eye(3)[None]))
    quat = quaternions(rot)
    np.testing.assert_allclose(np.linalg.norm(quat, axis=1), 1.0, atol=1e-12)
    assert np.all(quat[:, 3] >= 0)                                    # w >= 0: one of the two
    for k in range(rot.shape[0]):
        np.testing.assert_allclose(matrix(quat[k]), rot[k], atol=1e-12)


def test_trajectory_message_carries_times_and_positions_only() -> None:
    traj = servo_trajectory(np.zeros(5), np.array([0.3, -0.05, 0.0, 0.2, 0.0]), 0.2,
                            sample_period=0.4, joint_names=ARM.joint_names)
    msg = trajectory_msg(traj)
    assert list(msg.joint_names) == list(ARM.joint_names)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (0, 0)      # start now
    times = [p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec for p in msg.points]
    np.testing.assert_allclose(times, traj.times, atol=1e-9)
    assert msg.points[-1].time_from_start.sec == 1                        # 1.5 s: 1 s + 5e8 ns
    assert msg.points[-1].time_from_start.nanosec == 500_000_000
    np.testing.assert_array_equal([p.positions for p in msg.points], traj.positions)
    assert not any(len(p.velocities) or len(p.accelerations) for p in msg.points)


def test_path_message_has_one_pose_per_point_from_forward_kinematics() -> None:
    traj = servo_trajectory(np.zeros(5), np.array([0.4, 0.3, -0.2, 0.1, 0.5]), 0.2,
                            joint_names=ARM.joint_names)
    header = Header(frame_id='arm_base')
    path = path_msg(ARM, traj, header)
    assert path.header.frame_id == 'arm_base'
    assert len(path.poses) == len(traj.times)
    tool, axis = ARM.tool(traj.positions)
    for k, pose in enumerate(path.poses):
        assert pose.header.frame_id == 'arm_base'
        p, o = pose.pose.position, pose.pose.orientation
        np.testing.assert_allclose([p.x, p.y, p.z], tool[k], atol=1e-15)
        np.testing.assert_allclose(matrix([o.x, o.y, o.z, o.w])[:, 2], axis[k], atol=1e-12)
