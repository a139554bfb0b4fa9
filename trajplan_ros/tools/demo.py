"""
The ``trajplan demo`` subcommand: start the ROS 2 planner node and plan the paper's example.

It runs ``planner_node`` as a child process in a DDS domain of its own (localhost discovery),
calls its ``plan_trajectory`` service with the paper's target, prints the plan, the tool path's
last pose and the JointTrajectory the node published, then stops the node by its PID.

``PlannerProcess`` and ``ros_environment`` are shared with ``bench_node``. This module imports
rclpy only when the demo runs, so ``trajplan`` works without ROS 2.
"""
from __future__ import annotations

import argparse
import importlib.util
import math
import os
import queue
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, Mapping, Sequence

from trajplan_ros.planning.paper_experiment import PAPER_TARGET
from trajplan_ros.tools.arguments import finite_number

__all__ = ['PlannerProcess', 'add_parser', 'planner_command', 'ros_environment']



def planner_command() -> list[str]:
    """
    How to start the node: ``planner_node`` beside this Python (a venv's bin), else on PATH,
    else ``python -m trajplan_ros.ros.node`` (a source checkout).
    """
    beside = Path(sys.executable).with_name('planner_node')
    if beside.is_file() and os.access(beside, os.X_OK):
        return [str(beside)]
    found = shutil.which('planner_node')
    return [found] if found else [sys.executable, '-m', 'trajplan_ros.ros.node']


def ros_environment(base: Mapping[str, str] | None = None) -> dict[str, str]:
    """
    ``base`` (default os.environ) with a DDS domain of this process's own (1..100, from the
    pid), localhost-only discovery, and this Python's prefix on AMENT_PREFIX_PATH (where the
    pip-installed ROS 2 packages register themselves).
    """
    env = dict(os.environ if base is None else base)
    env['ROS_DOMAIN_ID'] = str(1 + os.getpid() % 100)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    prefixes = [p for p in env.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]
    if sys.prefix not in prefixes:
        env['AMENT_PREFIX_PATH'] = os.pathsep.join([*prefixes, sys.prefix])
    env['PYTHONUNBUFFERED'] = '1'
    return env


class PlannerProcess:
    """``planner_node`` as a child process; its log lines are collected as they come."""

    def __init__(self, ros_args: Sequence[str] = (), env: Mapping[str, str] | None = None,
                 argv: Sequence[str] | None = None) -> None:
        """Run ``argv`` (default: ``planner_command()``) with ``--ros-args ros_args``."""
        argv = list(argv or planner_command()) + (['--ros-args', *ros_args] if ros_args else [])
        self.argv = argv
        self.proc = subprocess.Popen(argv, env=dict(env or ros_environment()),
                                     stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, text=True)
        self.lines: list[str] = []
        self._eof = False
        self._cond = threading.Condition()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    @property
    def pid(self) -> int:
        return self.proc.pid

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            with self._cond:
                self.lines.append(line.rstrip('\n'))
                self._cond.notify_all()
        with self._cond:
            self._eof = True
            self._cond.notify_all()

    def wait_for(self, pattern: str, timeout: float, after: int = 0) -> re.Match[str] | None:
        """The first log line from index ``after`` on matching ``pattern``; None on timeout or exit."""
        regex = re.compile(pattern)
        found: list[re.Match[str]] = []

        def scan() -> bool:
            found[:] = [m for m in map(regex.search, self.lines[after:]) if m][:1]
            return bool(found) or self._eof

        with self._cond:
            self._cond.wait_for(scan, timeout=timeout)
        return found[0] if found else None

    def matches(self, pattern: str) -> list[re.Match[str]]:
        """Every log line so far that matches ``pattern``."""
        regex = re.compile(pattern)
        with self._cond:
            return [m for m in map(regex.search, self.lines) if m]

    def stop(self, sig: int = signal.SIGINT, timeout: float = 5.0) -> int:
        """``sig`` (SIGINT) by PID, SIGKILL after ``timeout`` s; the exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._reader.join(timeout=timeout)
        return self.proc.returncode


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        'demo', help="run the ROS 2 planner node and plan the paper's example through it",
        description='Start planner_node in a DDS domain of its own, call plan_trajectory with '
                    "the paper's target, print the plan and the published JointTrajectory, "
                    "and stop the node. Needs the ROS 2 packages: pip install '.[ros]'.")
    p.add_argument('--goal', nargs=3, type=finite_number, default=tuple(PAPER_TARGET.tolist()), metavar=('X', 'Y', 'Z'),
                   help="tool goal in metres (default: the paper's %(default)s)")
    p.add_argument('--timeout', type=float, default=60.0,
                   help='seconds to wait for the node and for each answer (default 60)')
    p.set_defaults(run=_run)


def _run(args: argparse.Namespace) -> int:
    env = ros_environment()
    os.environ.update(env)                 # this process joins the node's DDS domain
    if importlib.util.find_spec('rclpy') is None:
        raise ValueError("the demo needs ROS 2's Python packages: pip install '.[ros]'")
    node = PlannerProcess(env=env)
    print(f"started {' '.join(node.proc.args)} (pid {node.pid}), "
          f"ROS_DOMAIN_ID={env['ROS_DOMAIN_ID']}, localhost discovery")
    try:
        return _talk(node, tuple(args.goal), args.timeout)
    finally:
        code = node.stop()
        print(f'stopped planner_node (pid {node.pid}, exit code {code})')


def _talk(node: PlannerProcess, goal: tuple[float, float, float], timeout: float) -> int:
    import rclpy
    from nav_msgs.srv import GetPlan
    from rclpy.executors import SingleThreadedExecutor
    from trajectory_msgs.msg import JointTrajectory

    context = rclpy.Context()
    rclpy.init(context=context)
    client_node = rclpy.create_node('trajplan_demo', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(client_node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        received: queue.Queue[Any] = queue.Queue()
        sub = client_node.create_subscription(JointTrajectory, 'joint_trajectory', received.put, 10)
        client = client_node.create_client(GetPlan, 'plan_trajectory')
        if not client.wait_for_service(timeout_sec=timeout):
            print(f'no plan_trajectory service within {timeout:.0f} s; the node said:\n'
                  + '\n'.join(node.lines[-20:]), file=sys.stderr)
            return 1
        deadline = time.monotonic() + timeout    # the answer's trajectory must reach us too
        while sub.get_publisher_count() == 0 and time.monotonic() < deadline:
            threading.Event().wait(0.02)
        request = GetPlan.Request(tolerance=0.0)
        request.goal.pose.position.x, request.goal.pose.position.y, request.goal.pose.position.z = goal
        print(f'calling plan_trajectory, goal ({goal[0]}, {goal[1]}, {goal[2]}) m')
        answered = threading.Event()
        future = client.call_async(request)
        future.add_done_callback(lambda _: answered.set())
        if not answered.wait(timeout):
            print(f'no answer within {timeout:.0f} s', file=sys.stderr)
            return 1
        # the node answers first, then publishes the trajectory and logs the plan
        logged = node.wait_for(r'\]: (service call #1 .*)$', timeout)
        if logged:
            print(f'node log: {logged.group(1)}')
        path = future.result().plan
        if not path.poses:
            print('empty plan: the goal was not reached (see the node log above)')
            return 1
        try:
            trajectory = received.get(timeout=timeout)
        except queue.Empty:
            print(f'no JointTrajectory within {timeout:.0f} s', file=sys.stderr)
            return 1
        _print_plan(path, trajectory, goal)
        return 0
    finally:
        executor.shutdown()
        spinner.join(timeout=timeout)
        client_node.destroy_node()
        rclpy.try_shutdown(context=context)


def _print_plan(path: Any, trajectory: Any, goal: tuple[float, float, float]) -> None:
    last, first = trajectory.points[-1], trajectory.points[0]

    def seconds(d: Any) -> float:
        return d.sec + 1e-9 * d.nanosec

    print('planned joint angles [rad]: ' + '  '.join(
        f'{n}={q:+.6f}' for n, q in zip(trajectory.joint_names, last.positions)))
    print(f'motion time: {seconds(last.time_from_start):.4f} s')
    pose = path.poses[-1].pose
    p, o = pose.position, pose.orientation
    error = math.dist((p.x, p.y, p.z), goal)
    print(f"tool path: {len(path.poses)} poses in frame '{path.header.frame_id}'; last pose "
          f'position ({p.x:.6f}, {p.y:.6f}, {p.z:.6f}) m, orientation (x, y, z, w) '
          f'({o.x:.4f}, {o.y:.4f}, {o.z:.4f}, {o.w:.4f})')
    print(f'position error: {error:.3g} m')
    stamp = trajectory.header.stamp
    print(f'JointTrajectory on joint_trajectory: {len(trajectory.points)} points, joints '
          f"{', '.join(trajectory.joint_names)}; header.stamp {stamp.sec}.{stamp.nanosec:09d} "
          f'(start now); time_from_start {seconds(first.time_from_start):.3f} .. '
          f'{seconds(last.time_from_start):.3f} s; last velocities '
          f"{', '.join(f'{v:g}' for v in last.velocities)} rad/s")
