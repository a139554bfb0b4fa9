# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
pymoveit2 (PyPI 5.0.0) planning through the node, run as a process with moveit_msgs loadable.

``python pymoveit2_client.py JSON``: JSON names the ``namespace`` of move_group, the arm
(``joints``, ``base``, ``tip``), the ``start`` angles and a list of ``goals``, each of
``MoveIt2.plan``'s keywords (``position``, ``quat_xyzw``, ``tolerance_position``,
``tolerance_orientation``); prints one JSON line per goal: the trajectory's joint names, times
and positions, or null where pymoveit2 got none.
"""
from __future__ import annotations

import json
import sys
import threading

from pymoveit2 import MoveIt2
import rclpy
from rclpy.executors import MultiThreadedExecutor


def main() -> None:
    spec = json.loads(sys.argv[1])
    rclpy.init()
    node = rclpy.create_node('pymoveit2_test_client', namespace=spec['namespace'])
    moveit2 = MoveIt2(node=node, joint_names=spec['joints'], base_link_name=spec['base'],
                      end_effector_name=spec['tip'], group_name='arm')
    executor = MultiThreadedExecutor(2)
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    for goal in spec['goals']:
        # a request sent while discovery is still matching the service's reader is lost, and
        # pymoveit2 says None as for a failed plan: a second try tells the two apart
        for _ in range(2):
            trajectory = moveit2.plan(start_joint_state=spec['start'], timeout_sec=30.0, **goal)
            if trajectory is not None:
                break
        print(json.dumps(None if trajectory is None else {
            'joint_names': list(trajectory.joint_names),
            'times': [p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec
                      for p in trajectory.points],
            'positions': [list(p.positions) for p in trajectory.points]}), flush=True)
    executor.shutdown()
    spinner.join(timeout=10.0)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == '__main__':
    main()
