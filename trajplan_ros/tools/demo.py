# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The ``trajplan demo`` subcommand: start the ROS 2 planner node and plan the paper's example.

It runs ``planner_node`` as a child process in a DDS domain of its own (localhost discovery),
does what ``trajplan call --trajectory`` does with the paper's target (prints the published
JointTrajectory and the tool path's last pose), then stops the node by its PID. It waits for
the node's ``ready`` line first: a node that says it is compiling its kernels (the first start
after an install) gets as long as that takes. It imports rclpy only when it runs, so
``trajplan`` works without ROS 2.
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import subprocess
import sys

from trajplan_ros.tools.arguments import finite_number, UsageError
from trajplan_ros.tools.bench.paper_experiment import PAPER_TARGET
from trajplan_ros.tools.node_commands import call_planner
from trajplan_ros.tools.node_process import COMPILE_BOUND_S, PlannerProcess, ros_environment


__all__ = ['add_parser']


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``trajplan demo``."""
    p = sub.add_parser(
        'demo', help="run the ROS 2 planner node and plan the paper's example through it",
        description='Start planner_node in a DDS domain of its own, call plan_trajectory with '
                    "the paper's target, print the plan and the published JointTrajectory, "
                    "and stop the node. Needs the ROS 2 packages: pip install '.[ros]'.")
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
    from trajplan_ros.tools.ros_client import RosClient

    node = PlannerProcess(env=env)
    print(f"started {' '.join(node.proc.args)} (pid {node.pid}), "
          f"ROS_DOMAIN_ID={env['ROS_DOMAIN_ID']}, localhost discovery")
    try:
        _wait_until_ready(node, args.timeout)
        with RosClient('trajplan_demo') as ros:
            code = call_planner(ros, tuple(args.goal), service='plan_trajectory', tolerance=0.0,
                                timeout=args.timeout, trajectory_topic='joint_trajectory')
        logged = node.wait_for(r'\]: (service call #1 .*)$', args.timeout)
        print(f'node log: {logged.group(1)}' if logged else 'node log: nothing about the call')
        return code
    except TimeoutError as exc:
        print(f'{exc}; the node said:\n' + '\n'.join(node.lines[-20:]), file=sys.stderr)
        return 1
    finally:
        code = node.stop()
        print(f'stopped planner_node (pid {node.pid}, exit code {code})')


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
