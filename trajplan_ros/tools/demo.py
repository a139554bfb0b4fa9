# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The ``trajplan demo`` subcommand: start the ROS 2 planner node and plan the paper's example.

It runs ``planner_node`` as a child process in a DDS domain of its own (localhost discovery),
does what ``trajplan call --trajectory`` does with the paper's target (prints the published
JointTrajectory and the tool path's last pose), then stops the node by its PID. Where
control_msgs loads, it closes the loop instead: the node executes through the package's
demo_controller (``execution: action``), and two goals in a row are planned and executed, the
second from where the arm stopped (``trajplan call --wait-execution`` twice). It waits for
the node's ``ready`` line first: a node that says it is compiling its kernels (the first start
after an install) gets as long as that takes. It imports rclpy only when it runs, so
``trajplan`` works without ROS 2.
"""
from __future__ import annotations

import argparse
import importlib.util
import os
from pathlib import Path
import subprocess
import sys

from trajplan_ros.tools.arguments import finite_number, UsageError
from trajplan_ros.tools.bench.cases import PAPER_TARGET
from trajplan_ros.tools.node_commands import call_planner
from trajplan_ros.tools.node_process import (COMPILE_BOUND_S, planner_command, PlannerProcess,
                                             ros_environment)


__all__ = ['add_parser']

#: The closed loop's second goal (m), planned from where the arm stopped after the first.
SECOND_GOAL = (0.2, 0.1, 0.15)


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``trajplan demo``."""
    p = sub.add_parser(
        'demo', help="run the ROS 2 planner node and plan the paper's example through it",
        description='Start planner_node in a DDS domain of its own, call plan_trajectory with '
                    "the paper's target, print the plan and the published JointTrajectory, "
                    'and stop the node. Where control_msgs loads, execute it through '
                    'demo_controller instead, then a second goal from where the arm stopped. '
                    "Needs the ROS 2 packages: pip install '.[ros]'.")
    p.add_argument('--goal', nargs=3, type=finite_number, default=tuple(PAPER_TARGET.tolist()),
                   metavar=('X', 'Y', 'Z'), help="tool goal in metres (default: the paper's "
                                                 '%(default)s)')
    p.add_argument('--timeout', type=float, default=60.0,
                   help='seconds to wait for the node and for each answer (default 60)')
    p.set_defaults(run=_run)


def _run(args: argparse.Namespace) -> int:
    env = ros_environment()
    os.environ.update(env)                 # this process joins the node's DDS domain
    if importlib.util.find_spec('rclpy') is None:
        raise UsageError("the demo needs ROS 2's Python packages: pip install '.[ros]'")
    from trajplan_ros.ros.execution import action_type, HOW_TO
    from trajplan_ros.tools.ros_client import RosClient

    try:
        action_type()
        loop = True
    except ValueError:
        loop = False
        print('control_msgs does not load here: the motion is published on joint_trajectory, '
              f'not executed through a controller ({HOW_TO})')
    started = [PlannerProcess(env=env, argv=planner_command('demo_controller'))] if loop else []
    started.append(PlannerProcess(['-p', 'execution:=action'] if loop else [], env=env))
    node = started[-1]
    for process in started:
        print(f"started {' '.join(process.proc.args)} (pid {process.pid}), "
              f"ROS_DOMAIN_ID={env['ROS_DOMAIN_ID']}, localhost discovery")
    try:
        _wait_until_ready(node, args.timeout)
        with RosClient('trajplan_demo') as ros:
            goals = [tuple(args.goal), SECOND_GOAL] if loop else [tuple(args.goal)]
            for call, goal in enumerate(goals, 1):
                code = call_planner(ros, goal, service='plan_trajectory', tolerance=0.0,
                                    timeout=args.timeout, trajectory_topic=None if loop else
                                    'joint_trajectory', wait_execution=loop)
                logged = node.wait_for(rf'\]: (service call #{call} .*)$', args.timeout)
                print(f'node log: {logged.group(1)}' if logged else
                      'node log: nothing about the call')
                if code:
                    return code
        return 0
    except TimeoutError as exc:
        print(f'{exc}; the node said:\n' + '\n'.join(node.lines[-20:]), file=sys.stderr)
        return 1
    finally:
        for process in reversed(started):
            code = process.stop()
            print(f'stopped {Path(process.argv[0]).name} (pid {process.pid}, exit code {code})')


def _wait_until_ready(node: PlannerProcess, timeout: float) -> None:
    """Wait for the node's ``ready`` line: ``timeout`` s, or as long as a compile it announced."""
    said = node.wait_for(r'\]: ((?:ready:|compiling) .*)$', timeout)
    if said is None:
        raise TimeoutError(f'planner_node was not ready within {timeout:g} s')
    if said.group(1).startswith('compiling'):
        print(f'planner_node: {said.group(1)}', flush=True)
        if node.wait_for(r'\]: ready: ', COMPILE_BOUND_S) is None:
            try:
                code = node.proc.wait(timeout=5.0)     # its output ended: it is exiting
            except subprocess.TimeoutExpired:
                code = None
            raise TimeoutError('planner_node did not finish compiling' if code is None else
                               f'planner_node exited with code {code} while compiling')
        compiled = node.matches(r'\]: (compiled \d+ planning kernels in \S+ s)')
        if compiled:
            print(f'planner_node: {compiled[0].group(1)}', flush=True)
