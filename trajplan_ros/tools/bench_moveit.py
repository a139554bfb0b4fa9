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

``--quality``: the answers' quality on held-out region goals instead: goals of seeded random
configurations, each a sphere of ``--radius`` m from q = 0 clipped, against the reference
moving into the same sphere (``chain_bench.region_reference``, from the exact minimax
reference and 8 more starts). Target: at least 99 % of the answers within 0.1 % of it.

The node checks no collisions here (``collision_check:=false``), as the references do not.
Prints the figures; exits 0 when the target is met, 1 otherwise.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass, field
import os
import statistics
import sys
import tempfile
from typing import Any, Sequence

import numpy as np
from rcl_interfaces.srv import GetParameters
from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.ros.moveit_interfaces import moveit_types
from trajplan_ros.search.goal import Mode
from trajplan_ros.search.region import Region
from trajplan_ros.tools.bench.chain_bench import ChainCase, draw_chain_cases, region_cases
from trajplan_ros.tools.bench.runner import SUCCESS_GAP
from trajplan_ros.tools.bench_node import description_args, timed_call, tool_goals
from trajplan_ros.tools.moveit_requests import motion_request
from trajplan_ros.tools.node_process import PlannerProcess, ros_environment
from trajplan_ros.tools.ros_client import RosClient

__all__ = ['main']

#: How long the node may take to offer the service (a first start compiles its kernels).
START_S = 900.0
#: Random starts of each region reference beside the exact reference's joint goal.
REFERENCE_STARTS = 8
#: The share of answers within ``SUCCESS_GAP`` of their reference that meets the target.
QUALITY_TARGET = 0.99


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog='python -m trajplan_ros.tools.bench_moveit',
                                     description=__doc__.split('\n\n')[0])
    parser.add_argument('--calls', type=int, default=100, help='requests (default 100)')
    parser.add_argument('--seed', type=int, default=5, help='seed of the goals (default 5)')
    parser.add_argument('--radius', type=float, default=0.001,
                        help="the goal sphere's radius, m (default 0.001, pymoveit2's)")
    parser.add_argument('--urdf', metavar='FILE', help="plan for this URDF's chain")
    parser.add_argument('--tip-link', metavar='NAME', help="the chain's tip link, with --urdf")
    parser.add_argument('--quality', action='store_true',
                        help="measure the answers' motion times against region references")
    args = parser.parse_args(argv)
    args.scene = None
    try:
        _, srv = moveit_types()
    except ValueError as exc:
        print(exc, file=sys.stderr)
        return 2
    arm = ArmModel.from_urdf(args.urdf, None, args.tip_link) if args.urdf else paper_arm()
    cases = None
    if args.quality:
        drawn, _ = draw_chain_cases(arm, args.calls, mode=Mode.FREE, random_starts=False,
                                    seed=args.seed)
        cases = region_cases(drawn, arm, Mode.FREE, Region(args.radius, 0.0), REFERENCE_STARTS)
        goals = np.array([case.goal for case in cases])
    else:
        goals = tool_goals(arm, args.calls, args.seed)
    start = dict(zip(arm.joint_names, np.clip(0.0, arm.lower, arm.upper).tolist()))  # as the node
    code, calls = _calls(args, srv, goals, start)
    arm_name = args.urdf or 'the paper arm'
    if cases is not None:
        quality = _quality(cases, calls, arm_name, args.radius)
        return quality if code == 0 else 1
    return _overhead(calls, arm_name, args.radius) if code == 0 else 1


@dataclass
class Calls:
    """What the requests came to: each one's round trip, planning time, code, motion time."""

    trips: list[float] = field(default_factory=list)
    plans: list[float] = field(default_factory=list)
    codes: list[int] = field(default_factory=list)
    motions: list[float] = field(default_factory=list)        # s; inf without a trajectory
    empties: list[float] = field(default_factory=list)        # empty calls' round trips


def _calls(args: argparse.Namespace, srv: Any, goals: np.ndarray,
           start: dict[str, float]) -> tuple[int, Calls]:
    """Send the requests to a node run as move_group; return its exit code and the calls."""
    env = ros_environment()
    os.environ.update(env)                       # this process joins the node's domain
    folder = tempfile.TemporaryDirectory(prefix='trajplan-bench-moveit-')
    node = PlannerProcess(['-r', '__node:=move_group', '-p', 'moveit_interfaces:=true',
                           '-p', 'collision_check:=false',
                           *description_args(args, folder.name)], env=env)
    ros = RosClient('trajplan_bench_moveit')
    calls = Calls()
    try:
        client = ros.client(srv.GetMotionPlan, 'plan_kinematic_path', START_S)
        empty = ros.client(GetParameters, 'move_group/get_parameters', START_S)
        node.wait_for(r'move_group\]: ready: ', START_S)
        for goal in goals:
            request = srv.GetMotionPlan.Request(motion_plan_request=motion_request(
                goal.tolist(), radius=args.radius, start=start))
            answer, trip = timed_call(ros, client, request)
            response = answer.motion_plan_response
            calls.trips.append(trip)
            calls.plans.append(response.planning_time)
            calls.codes.append(response.error_code.val)
            points = response.trajectory.joint_trajectory.points
            calls.motions.append(points[-1].time_from_start.sec
                                 + 1e-9 * points[-1].time_from_start.nanosec
                                 if points else np.inf)
            if not args.quality:
                calls.empties.append(timed_call(ros, empty, GetParameters.Request())[1])
    finally:
        ros.close()
        code = node.stop()
        folder.cleanup()
    return code, calls


def _overhead(calls: Calls, arm_name: str, radius: float) -> int:
    """Print the round trips beside the plans; return 0 when the target is met."""
    overhead = np.subtract(calls.trips, calls.plans)
    bound = 2 * statistics.median(calls.empties)
    met = statistics.median(overhead) <= bound
    print(f'plan_kinematic_path: {len(calls.trips)} requests ({arm_name}, a sphere of '
          f'{radius:g} m), {calls.codes.count(1)} SUCCESS')
    for name, values in (('round trip', calls.trips), ('plan (planning_time)', calls.plans),
                         ('overhead = trip - plan', overhead),
                         ('empty service call', calls.empties)):
        print(f'  {name:<24} median {1e3 * statistics.median(values):.2f} ms, '
              f'p90 {1e3 * float(np.percentile(values, 90)):.2f} ms')
    print(f'  target: median overhead <= 2 x the empty call = {1e3 * bound:.2f} ms: '
          f"{'met' if met else 'NOT MET'}")
    return 0 if met else 1


def _quality(cases: Sequence[ChainCase], calls: Calls, arm_name: str, radius: float) -> int:
    """Print the answers' gaps to the region references; return 0 when the target is met."""
    gaps = np.array([m / c.reference_time - 1.0 if c.reference_time > 0 else m
                     for m, c in zip(calls.motions, cases)])
    within = float(np.mean(gaps <= SUCCESS_GAP))
    met = within >= QUALITY_TARGET
    others = sorted({c for c in calls.codes if c != 1})
    failed = ''.join(f', {calls.codes.count(c)} with code {c}' for c in others)
    print(f'plan_kinematic_path: {len(cases)} held-out region goals ({arm_name}, spheres of '
          f'{radius:g} m), {calls.codes.count(1)} SUCCESS{failed}')
    print(f'  within {100 * SUCCESS_GAP:g} % of the region reference: {100 * within:.1f} %; '
          f'median gap {100 * float(np.median(gaps)):+.3f} %, worst '
          f'{100 * float(np.max(gaps)):+.2f} %')
    print(f'  target: >= {100 * QUALITY_TARGET:g} % within {100 * SUCCESS_GAP:g} %: '
          f"{'met' if met else 'NOT MET'}")
    return 0 if met else 1


if __name__ == '__main__':
    sys.exit(main())
