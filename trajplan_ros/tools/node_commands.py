# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
``trajplan call`` and ``trajplan goal``: talk to a running planner node from a plain venv.

They do what ``ros2 service call plan_trajectory nav_msgs/srv/GetPlan ...`` and
``ros2 topic pub --once goal geometry_msgs/msg/Point ...`` would, for users without the ``ros2``
command line (it is not on PyPI). Both use the ROS environment as it is (``ROS_DOMAIN_ID``,
``ROS_AUTOMATIC_DISCOVERY_RANGE``, namespaces through the names given) and import rclpy only
when they run, so ``trajplan`` works without ROS 2.
"""
from __future__ import annotations

import argparse
import importlib.util
import math
import queue
from typing import Any

from trajplan_ros.tools.arguments import finite_number, UsageError


__all__ = ['add_call_parser', 'add_goal_parser', 'call_planner', 'print_trajectory']

Goal = tuple[float, float, float]


def _seconds(duration: Any) -> float:
    return duration.sec + 1e-9 * duration.nanosec


def _need_rclpy() -> None:
    if importlib.util.find_spec('rclpy') is None:
        raise UsageError("this command needs ROS 2's Python packages: pip install '.[ros]' "
                         '(or source a ROS 2 installation)')


def print_path(path: Any, goal: Goal) -> None:
    """Print a GetPlan answer's tool path: its size, frame, last pose and error to the goal."""
    pose = path.poses[-1].pose
    p, o = pose.position, pose.orientation
    print(f"tool path: {len(path.poses)} poses in frame '{path.header.frame_id}'; last pose "
          f'position ({p.x:.6f}, {p.y:.6f}, {p.z:.6f}) m, orientation (x, y, z, w) '
          f'({o.x:.4f}, {o.y:.4f}, {o.z:.4f}, {o.w:.4f})')
    print(f'position error: {math.dist((p.x, p.y, p.z), goal):.3g} m')


def print_trajectory(trajectory: Any, topic: str) -> None:
    """Print a JointTrajectory: its joint goal, duration and the controller-relevant fields."""
    last, first = trajectory.points[-1], trajectory.points[0]
    print('planned joint angles [rad]: ' + '  '.join(
        f'{n}={q:+.6f}' for n, q in zip(trajectory.joint_names, last.positions)))
    print(f'motion time: {_seconds(last.time_from_start):.4f} s')
    stamp = trajectory.header.stamp
    print(f'JointTrajectory on {topic}: {len(trajectory.points)} points, joints '
          f"{', '.join(trajectory.joint_names)}; header.stamp {stamp.sec}.{stamp.nanosec:09d} "
          f'(start now); time_from_start {_seconds(first.time_from_start):.3f} .. '
          f'{_seconds(last.time_from_start):.3f} s; last velocities '
          f"{', '.join(f'{v:g}' for v in last.velocities)} rad/s")


def _next(box: queue.Queue[Any], timeout: float, what: str) -> Any:
    try:
        return box.get(timeout=timeout)
    except queue.Empty:
        raise TimeoutError(f'no {what} within {timeout:g} s') from None


def call_planner(ros: Any, goal: Goal, *, service: str, tolerance: float, timeout: float,
                 trajectory_topic: str | None) -> int:
    """
    Call the planning service with ``goal`` and print the answer; 0 for a plan, 1 for none.

    With ``trajectory_topic``, also wait for the trajectory the node publishes there and print
    it (the node answers first, then publishes).
    """
    from nav_msgs.srv import GetPlan
    from trajectory_msgs.msg import JointTrajectory
    from trajplan_ros.tools.ros_client import plan_request

    box = ros.inbox(JointTrajectory, trajectory_topic, timeout) if trajectory_topic else None
    print(f'calling {service}, goal ({goal[0]}, {goal[1]}, {goal[2]}) m')
    path = ros.call(GetPlan, service, plan_request(goal, tolerance), timeout).plan
    if not path.poses:
        print('empty plan: the node did not plan this goal (its log says why)')
        return 1
    if box is not None:
        print_trajectory(_next(box, timeout, f'JointTrajectory on {trajectory_topic}'),
                         trajectory_topic)
    print_path(path, goal)
    return 0


def _run_call(args: argparse.Namespace) -> int:
    _need_rclpy()
    from trajplan_ros.tools.ros_client import RosClient

    with RosClient('trajplan_call') as ros:
        return call_planner(ros, tuple(args.xyz), service=args.service,
                            tolerance=args.tolerance, timeout=args.timeout,
                            trajectory_topic=args.trajectory)


def _run_goal(args: argparse.Namespace) -> int:
    _need_rclpy()
    from geometry_msgs.msg import Point
    from trajectory_msgs.msg import JointTrajectory
    from trajplan_ros.tools.ros_client import RosClient

    x, y, z = args.xyz
    with RosClient('trajplan_goal') as ros:
        box = (ros.inbox(JointTrajectory, args.trajectory, args.timeout) if args.trajectory
               else None)
        ros.publish(Point, args.topic, Point(x=x, y=y, z=z), args.timeout)
        print(f'published goal ({x}, {y}, {z}) m on {args.topic}')
        if box is not None:
            print_trajectory(_next(box, args.timeout, f'JointTrajectory on {args.trajectory}'),
                             args.trajectory)
    return 0


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument('xyz', nargs=3, type=finite_number, metavar=('X', 'Y', 'Z'),
                   help="tool goal in metres, in the planner's base frame")
    p.add_argument('--timeout', type=float, default=30.0,
                   help='seconds to wait for the node and for each answer (default 30)')
    p.add_argument('--trajectory', metavar='TOPIC', nargs='?', const='joint_trajectory',
                   help='also print the JointTrajectory the node publishes (on TOPIC, default '
                        'joint_trajectory)')


def add_call_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``trajplan call``: the planning service, as ``ros2 service call`` would."""
    p = sub.add_parser('call', help="call a running planner node's plan_trajectory service",
                       description='Send a GetPlan request to a running planner node and print '
                                   'the answer. Exit status 0: a plan; 1: an empty plan or no '
                                   'answer in time.')
    _common(p)
    p.add_argument('--service', default='plan_trajectory',
                   help='service name (default plan_trajectory; e.g. /arm1/plan_trajectory)')
    p.add_argument('--tolerance', type=finite_number, default=0.0,
                   help="largest error in metres that counts as reached (0: the node's "
                        'tolerance parameter)')
    p.set_defaults(run=_run_call)


def add_goal_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``trajplan goal``: one goal on the goal topic, as ``ros2 topic pub --once`` would."""
    p = sub.add_parser('goal', help='publish a goal to a running planner node',
                       description='Publish one geometry_msgs/Point on the goal topic, once the '
                                   'node subscribes, and wait until it has been received.')
    _common(p)
    p.add_argument('--topic', default='goal', help='goal topic (default goal)')
    p.set_defaults(run=_run_goal)
