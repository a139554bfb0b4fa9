# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
plan_kinematic_path's round trip beside the plan: ``python -m trajplan_ros.tools.bench_moveit``.

The node runs as move_group with ``moveit_interfaces`` (a child process, a DDS domain of its
own); this process is a MoveIt client. ``--calls`` GetMotionPlan requests on tool positions of
seeded random in-limit configurations (a sphere of ``--radius`` m, from q = 0 clipped to the
limits, as pymoveit2 sends them), each sent when the last is answered; as many empty service
calls (the node's get_parameters with no name) between them. A call's overhead is its round
trip minus the plan's own time (the answer's ``planning_time``, the library's
``plan_time_s``). Target: the median overhead at most twice the median empty round trip of
the same run. moveit_msgs must load here (export what build_ros_interfaces.sh prints).

Prints the figures; exits 0 when the target is met, 1 otherwise.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
from typing import Sequence

import numpy as np
from rcl_interfaces.srv import GetParameters
from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.ros.moveit_interfaces import moveit_types
from trajplan_ros.tools.bench_node import description_args, timed_call, tool_goals
from trajplan_ros.tools.moveit_requests import motion_request
from trajplan_ros.tools.node_process import PlannerProcess, ros_environment
from trajplan_ros.tools.ros_client import RosClient

__all__ = ['main']

#: How long the node may take to offer the service (a first start compiles its kernels).
START_S = 900.0


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog='python -m trajplan_ros.tools.bench_moveit',
                                     description=__doc__.split('\n\n')[0])
    parser.add_argument('--calls', type=int, default=100, help='requests (default 100)')
    parser.add_argument('--seed', type=int, default=5, help='seed of the goals (default 5)')
    parser.add_argument('--radius', type=float, default=0.001,
                        help="the goal sphere's radius, m (default 0.001, pymoveit2's)")
    parser.add_argument('--urdf', metavar='FILE', help="plan for this URDF's chain")
    parser.add_argument('--tip-link', metavar='NAME', help="the chain's tip link, with --urdf")
    args = parser.parse_args(argv)
    args.scene = None
    try:
        _, srv = moveit_types()
    except ValueError as exc:
        print(exc, file=sys.stderr)
        return 2
    arm = ArmModel.from_urdf(args.urdf, None, args.tip_link) if args.urdf else paper_arm()
    goals = tool_goals(arm, args.calls, args.seed)
    start = dict(zip(arm.joint_names, np.clip(0.0, arm.lower, arm.upper).tolist()))  # as the node
    env = ros_environment()
    os.environ.update(env)                       # this process joins the node's domain
    folder = tempfile.TemporaryDirectory(prefix='trajplan-bench-moveit-')
    node = PlannerProcess(['-r', '__node:=move_group', '-p', 'moveit_interfaces:=true',
                           *description_args(args, folder.name)], env=env)
    ros = RosClient('trajplan_bench_moveit')
    try:
        client = ros.client(srv.GetMotionPlan, 'plan_kinematic_path', START_S)
        empty = ros.client(GetParameters, 'move_group/get_parameters', START_S)
        node.wait_for(r'move_group\]: ready: ', START_S)
        trips, plans, empties, codes = [], [], [], []
        for goal in goals:
            request = srv.GetMotionPlan.Request(motion_plan_request=motion_request(
                goal.tolist(), radius=args.radius, start=start))
            answer, trip = timed_call(ros, client, request)
            response = answer.motion_plan_response
            trips.append(trip)
            plans.append(response.planning_time)
            codes.append(response.error_code.val)
            empties.append(timed_call(ros, empty, GetParameters.Request())[1])
    finally:
        ros.close()
        code = node.stop()
        folder.cleanup()
    overhead = np.subtract(trips, plans)
    bound = 2 * statistics.median(empties)
    met = statistics.median(overhead) <= bound
    arm_name = args.urdf or 'the paper arm'
    print(f'plan_kinematic_path: {len(goals)} requests ({arm_name}, a sphere of '
          f'{args.radius:g} m), {codes.count(1)} SUCCESS')
    for name, values in (('round trip', trips), ('plan (planning_time)', plans),
                         ('overhead = trip - plan', overhead), ('empty service call', empties)):
        print(f'  {name:<24} median {1e3 * statistics.median(values):.2f} ms, '
              f'p90 {1e3 * float(np.percentile(values, 90)):.2f} ms')
    print(f'  target: median overhead <= 2 x the empty call = {1e3 * bound:.2f} ms: '
          f"{'met' if met else 'NOT MET'}")
    return 0 if met and code == 0 else 1


if __name__ == '__main__':
    sys.exit(main())
