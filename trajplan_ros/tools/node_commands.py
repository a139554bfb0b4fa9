# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
``trajplan call`` and ``trajplan goal``: talk to a running planner node from a plain venv.

They do what ``ros2 service call plan_trajectory nav_msgs/srv/GetPlan ...`` and
``ros2 topic pub --once goal geometry_msgs/msg/Point ...`` would, for users without the ``ros2``
command line (it is not on PyPI). Both subscribe to the node's ``plan_results`` before they
send, so that a goal the node does not plan comes back with its reason (on stderr, exit 1): a
call is found there by its request's ``goal.header.stamp``, the client's clock at sending, a
goal by its point. With ``--wait-execution`` they then wait for the execution statuses of the
same request (a node whose ``execution`` is ``action``) and print how the controller ended
the motion (exit 1 unless it was executed). Both use the ROS environment as it is
(``ROS_DOMAIN_ID``, ``ROS_AUTOMATIC_DISCOVERY_RANGE``, namespaces through the names given) and
import rclpy only when they run, so ``trajplan`` works without ROS 2.
"""
from __future__ import annotations

import argparse
import importlib.util
import math
import queue
import sys
import time
from typing import Any, Callable

from trajplan_ros.planning.planner import describe_residual
from trajplan_ros.tools.arguments import finite_number, UsageError


__all__ = ['add_call_parser', 'add_goal_parser', 'call_planner', 'print_trajectory']

Goal = tuple[float, float, float]


def _seconds(duration: Any) -> float:
    return duration.sec + 1e-9 * duration.nanosec


def _need_rclpy() -> None:
    if importlib.util.find_spec('rclpy') is None:
        raise UsageError("this command needs ROS 2's Python packages: pip install '.[ros]' "
                         '(or source a ROS 2 installation)')


def print_path(path: Any, goal: Goal, frame: str = '') -> None:
    """
    Print a GetPlan answer's tool path: its size, frame, last pose and error to the goal.

    The error only for a goal in the path's frame (``frame`` empty or the same).
    """
    pose = path.poses[-1].pose
    p, o = pose.position, pose.orientation
    print(f"tool path: {len(path.poses)} poses in frame '{path.header.frame_id}'; last pose "
          f'position ({p.x:.6f}, {p.y:.6f}, {p.z:.6f}) m, orientation (x, y, z, w) '
          f'({o.x:.4f}, {o.y:.4f}, {o.z:.4f}, {o.w:.4f})')
    if frame in ('', path.header.frame_id):
        print(f"position error: {describe_residual(math.dist((p.x, p.y, p.z), goal), 'm')}")


def print_trajectory(trajectory: Any, topic: str) -> None:
    """Print a JointTrajectory: its joint goal, duration and the controller-relevant fields."""
    last, first = trajectory.points[-1], trajectory.points[0]
    print('planned joint angles [rad]: ' + '  '.join(
        f'{n}={q:+.6f}' for n, q in zip(trajectory.joint_names, last.positions)))
    print(f'motion time: {_seconds(last.time_from_start):.4f} s')
    from trajplan_ros.ros.outcomes import describe_stamp

    stamp = describe_stamp((trajectory.header.stamp.sec, trajectory.header.stamp.nanosec))
    print(f'JointTrajectory on {topic}: {len(trajectory.points)} points, joints '
          f"{', '.join(trajectory.joint_names)}; header.stamp {stamp} "
          f'(start now); time_from_start {_seconds(first.time_from_start):.3f} .. '
          f'{_seconds(last.time_from_start):.3f} s; points carry {_fields(last)}')


def _fields(point: Any) -> str:
    """Name the fields a JointTrajectoryPoint carries."""
    return ', '.join(name for name in ('positions', 'velocities', 'accelerations')
                     if len(getattr(point, name)))


def _next(box: queue.Queue[Any], timeout: float, what: str,
          mine: Callable[[Any], bool] = lambda _: True) -> Any:
    """Return the first message in ``box`` that is ``mine``, waiting up to ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            msg = box.get(timeout=max(deadline - time.monotonic(), 0.0))
        except queue.Empty:
            raise TimeoutError(f'no {what} within {timeout:g} s') from None
        if mine(msg):
            return msg


def _outcome(box: queue.Queue[Any], timeout: float, what: str,
             mine: Callable[[dict[str, str]], bool], stage: str = 'plan') -> dict[str, str]:
    """
    Wait for the node's status of the caller's request at ``stage``; return its values.

    ``mine`` tells the caller's statuses by their values (``ros.outcomes``); the values get
    the status's message as ``message``.
    """
    from trajplan_ros.ros.outcomes import outcome_values, TOPIC

    def values(msg: Any) -> dict[str, str]:
        return {**outcome_values(msg), 'message': msg.message, 'name': msg.name}

    msg = _next(box, timeout, f'{stage} status of {what} on {TOPIC}',
                lambda m: mine(v := values(m)) and v.get('stage', 'plan') == stage)
    return values(msg)


def _line(values: dict[str, str]) -> str:
    return f"{values['status']}: {values['message']}"


def _execution(box: queue.Queue[Any], timeout: float, what: str, plan: dict[str, str]) -> int:
    """
    Print how the controller ended the planned motion of ``plan``: 0 executed, else 1.

    Its statuses are the ones with the plan's name (the node's job): another request to the
    same goal has another.
    """
    from trajplan_ros.ros.outcomes import TERMINAL

    if plan['status'] != 'succeeded':
        print(f'trajplan: not executed: the plan ended {_line(plan)}', file=sys.stderr)
        return 1

    def mine(v: dict[str, str]) -> bool:
        return v['name'] == plan['name']

    bound = timeout + float(plan['motion_time_s'] or 0)
    try:
        while (values := _outcome(box, bound, what, mine, 'execution'))['status'] not in TERMINAL:
            print(f"execution: {values['status']}")
    except TimeoutError as exc:
        raise TimeoutError(f"{exc} (is the node's execution parameter action?)") from None
    if values['status'] != 'executed':
        print(f'trajplan: not executed: {_line(values)}', file=sys.stderr)
        return 1
    print(f"executed: {values['message']}")
    return 0


def _is_point(goal: Goal) -> Callable[[dict[str, str]], bool]:
    """Tell a topic goal's outcome by its point (the node writes it back exactly)."""
    return lambda v: v['request'] == 'goal' and tuple(
        float(v[axis]) for axis in 'xyz') == tuple(float(c) for c in goal)


def _has_stamp(stamp: str) -> Callable[[dict[str, str]], bool]:
    """Tell a stamped topic goal's outcome by its stamp."""
    return lambda v: v['request'] == 'goal' and v['stamp'] == stamp


def call_planner(ros: Any, goal: Goal, *, service: str, tolerance: float, timeout: float,
                 trajectory_topic: str | None, results_topic: str | None = None,
                 frame: str = '', wait_execution: bool = False) -> int:
    """
    Call the planning service with ``goal`` and print the answer; 0 for a plan, 1 for none.

    ``frame``: the goal's frame_id (empty: the node's base frame). With ``trajectory_topic``,
    also wait for the trajectory the node publishes there and print it (the node answers
    first, then publishes). With ``wait_execution``, then wait for the controller's end of
    the motion and print it: 1 unless executed.
    """
    from diagnostic_msgs.msg import DiagnosticStatus
    from nav_msgs.srv import GetPlan
    from trajectory_msgs.msg import JointTrajectory
    from trajplan_ros.ros import outcomes
    from trajplan_ros.tools.ros_client import plan_request

    ros.client(GetPlan, service, timeout)                 # the node first, then its results
    results = ros.inbox(DiagnosticStatus, results_topic or _beside(service, outcomes.TOPIC),
                        timeout, outcomes.QOS)
    box = ros.inbox(JointTrajectory, trajectory_topic, timeout) if trajectory_topic else None
    where = f" in frame '{frame}'" if frame else ''
    print(f'calling {service}, goal ({goal[0]}, {goal[1]}, {goal[2]}) m{where}')
    request = plan_request(goal, tolerance)
    request.goal.header.frame_id = frame
    request.goal.header.stamp = ros.node.get_clock().now().to_msg()
    stamp = outcomes.describe_stamp((request.goal.header.stamp.sec,
                                     request.goal.header.stamp.nanosec))
    path = ros.call(GetPlan, service, request, timeout).plan

    def mine(v: dict[str, str]) -> bool:
        return v['request'] == 'service call' and v['stamp'] == stamp

    if not path.poses:
        print(f"trajplan: not planned: {_line(_outcome(results, timeout, 'the call', mine))}",
              file=sys.stderr)
        return 1
    if box is not None:
        print_trajectory(_next(box, timeout, f'JointTrajectory on {trajectory_topic}'),
                         trajectory_topic)
    print_path(path, goal, frame)
    if wait_execution:
        return _execution(results, timeout, 'the call',
                          _outcome(results, timeout, 'the call', mine))
    return 0


def _run_call(args: argparse.Namespace) -> int:
    _need_rclpy()
    from trajplan_ros.tools.ros_client import RosClient

    if args.plan_only and args.wait_execution:
        raise UsageError('--wait-execution: a plan from compute_plan (--plan-only) is never '
                         'executed')
    with RosClient('trajplan_call') as ros:
        service = args.service or ('compute_plan' if args.plan_only else 'plan_trajectory')
        return call_planner(ros, _goal(args), service=service,
                            tolerance=args.tolerance, timeout=args.timeout,
                            trajectory_topic=args.trajectory, results_topic=args.results,
                            frame=args.frame, wait_execution=args.wait_execution)


def _run_goal(args: argparse.Namespace) -> int:
    _need_rclpy()
    from diagnostic_msgs.msg import DiagnosticStatus
    from geometry_msgs.msg import Point, PoseStamped
    from std_msgs.msg import Header
    from trajectory_msgs.msg import JointTrajectory
    from trajplan_ros.ros import outcomes
    from trajplan_ros.tools.ros_client import RosClient

    x, y, z = goal = _goal(args)
    topic = args.topic or ('goal_pose' if args.frame else 'goal')
    kind = PoseStamped if args.frame else Point
    with RosClient('trajplan_goal') as ros:
        results = ros.inbox(DiagnosticStatus, args.results or _beside(topic, outcomes.TOPIC),
                            args.timeout, outcomes.QOS)
        box = (ros.inbox(JointTrajectory, args.trajectory, args.timeout) if args.trajectory
               else None)
        ros.publisher(kind, topic, args.timeout)        # matched: the history has come
        while not results.empty():                # earlier goals' outcomes (history): not ours
            results.get_nowait()
        if args.frame:                            # told apart by its stamp, as a call is
            msg = PoseStamped(header=Header(frame_id=args.frame,
                                            stamp=ros.node.get_clock().now().to_msg()))
            msg.pose.position, msg.pose.orientation.w = Point(x=x, y=y, z=z), 1.0
            ours = _has_stamp(outcomes.describe_stamp((msg.header.stamp.sec,
                                                       msg.header.stamp.nanosec)))
        else:
            msg, ours = Point(x=x, y=y, z=z), _is_point(goal)
        ros.publish(kind, topic, msg, timeout=args.timeout)
        where = f" in frame '{args.frame}'" if args.frame else ''
        print(f'published goal ({x}, {y}, {z}) m{where} on {topic}')
        plan = _outcome(results, args.timeout, 'the goal', ours)
        if plan['status'] != 'succeeded':
            print(f'trajplan: not planned: {_line(plan)}', file=sys.stderr)
            return 1
        print(_line(plan))
        if box is not None:
            print_trajectory(_next(box, args.timeout, f'JointTrajectory on {args.trajectory}'),
                             args.trajectory)
        if args.wait_execution:
            return _execution(results, args.timeout, 'the goal', plan)
    return 0


def _beside(name: str, topic: str) -> str:
    """Return ``topic`` in the namespace of ``name`` (``/arm1/goal`` -> ``/arm1/plan_results``)."""
    namespace, _, _ = name.rpartition('/')
    return f'{namespace}/{topic}' if namespace or name.startswith('/') else topic


def _goal(args: argparse.Namespace) -> Goal:
    return (args.x, args.y, args.z)


def _common(p: argparse.ArgumentParser) -> None:
    for axis in 'xyz':
        p.add_argument(axis, type=finite_number, metavar=axis.upper(),
                       help=f"tool goal's {axis} in metres, in the planner's base frame "
                            '(or --frame)')
    p.add_argument('--timeout', type=float, default=30.0,
                   help='seconds to wait for the node and for each answer (default 30)')
    p.add_argument('--trajectory', metavar='TOPIC', nargs='?', const='joint_trajectory',
                   help='also print the JointTrajectory the node publishes (on TOPIC, default '
                        'joint_trajectory)')
    p.add_argument('--wait-execution', action='store_true',
                   help='then wait for the controller to end the motion (a node with execution '
                        'action) and print how; exit status 1 unless it was executed')
    p.add_argument('--results', metavar='TOPIC',
                   help="the node's plan_results topic (default: plan_results beside the "
                        'service or goal topic)')


def add_call_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``trajplan call``: the planning service, as ``ros2 service call`` would."""
    p = sub.add_parser('call', help="call a running planner node's plan_trajectory service",
                       description='Send a GetPlan request to a running planner node and print '
                                   'the answer. Exit status 0: a plan; 1: no plan (the reason, '
                                   "from the node's plan_results, on stderr) or no answer in "
                                   'time.')
    _common(p)
    p.add_argument('--service',
                   help='service name (default plan_trajectory, or compute_plan with '
                        '--plan-only; e.g. /arm1/plan_trajectory)')
    _frame_argument(p)
    p.add_argument('--plan-only', action='store_true',
                   help='call compute_plan: the plan is answered, not sent to the controller')
    p.add_argument('--tolerance', type=finite_number, default=0.0,
                   help="largest error in metres that counts as reached (0: the node's "
                        'tolerance parameter)')
    p.set_defaults(run=_run_call)


def add_goal_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``trajplan goal``: one goal on the goal topic, as ``ros2 topic pub --once`` would."""
    p = sub.add_parser('goal', help='publish a goal to a running planner node',
                       description='Publish one geometry_msgs/Point on the goal topic (with '
                                   '--frame a PoseStamped on goal_pose), once the '
                                   "node subscribes, and wait for its outcome on the node's "
                                   'plan_results. Exit status 0: planned; 1: not planned (the '
                                   'reason on stderr) or no answer in time.')
    _common(p)
    _frame_argument(p)
    p.add_argument('--topic', help='goal topic (default goal; goal_pose with --frame, where a '
                                   "PoseStamped goes, its orientation the identity: the node's "
                                   'goal_orientation approach or pose would plan to it)')
    p.set_defaults(run=_run_goal)


def _frame_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument('--frame', default='',
                   help="the goal's frame: a link of the robot's URDF, or any frame tf knows "
                        "where the node has tf2 (default: the node's base_frame)")
