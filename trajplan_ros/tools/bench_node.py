# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Benchmark of the ROS 2 planner node over DDS: ``python -m trajplan_ros.tools.bench_node``.

The node runs as a child process (``node_process.PlannerProcess``: a DDS domain of its own,
localhost discovery) with its default parameters; this process is its client.

0. Start-up: when the service is offered, when a first call (``compute_plan``, sent as soon as
   the service is offered) is answered, and when the node is ready to plan (its kernels
   compiled or loaded). Targets: the service within 30 s of the start, and the first answer
   within 30 s (90 s with ``--scene``), also on the first start after an install, when the
   node compiles the kernels its plans need (run it with an empty ``NUMBA_CACHE_DIR`` to see
   that case). At the end, the node's peak resident memory: at most 250 MB without collision
   checking, 400 MB with ``--scene`` (``--urdf`` with meshes and a scene file).

1. Service overhead. ``--calls`` plan_trajectory calls on tool positions of seeded random
   in-limit configurations, each sent when the node is idle (it has logged the call before, its
   last step). A call's overhead is its round trip measured here (request sent to response
   callback) minus the time of the plan itself, ``PlanResult.plan_time_s``, which the node logs
   for every plan ("planned in X ms"): everything around ``plan`` (DDS both ways, both
   executors, the worker hand-over, the tool path message and this client's decoding of it).
   The overhead grows with the path (one pose per trajectory point), so a least-squares line
   over the pose count is printed too. As a cross-check that the logged figure is the plan's
   own cost, ``plan`` is also timed in this process, before the node starts, on the same goals
   from the same starts (the node starts each plan where the last trajectory ended). Then as
   many calls back to back, each sent as soon as the last answer is in. Target: median
   overhead (idle node) at most 5 ms.
2. Goal stream. ``--goals`` goals published on ``goal`` at ``--rate`` Hz while a parameter get
   goes to the node every 10 ms, after a warm-up that makes sure publisher and node have
   matched. Targets: every goal is either planned or logged as dropped, and every parameter
   get is answered within 20 ms (the kernels release the GIL), until every goal is
   accounted for. ``--urdf FILE --tip-link NAME`` plans another arm (a Panda: the longest plans).

Prints the figures; exits 0 when every target is met, 1 otherwise.
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import platform
import re
import statistics
import sys
import tempfile
import threading
import time
from typing import Any, Sequence

from geometry_msgs.msg import Point
from nav_msgs.srv import GetPlan
import numpy as np
from rcl_interfaces.srv import GetParameters
from rclpy.utilities import get_rmw_implementation_identifier
from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.planning.planner import describe_goal, plan, prepare
from trajplan_ros.tools.node_process import (COMPILE_BOUND_S, PlannerProcess, ros_environment,
                                             rss_mb)
from trajplan_ros.tools.ros_client import plan_request, RosClient


__all__ = ['description_args', 'main', 'timed_call', 'tool_goals']

#: The targets: the node's own overhead per call, and a parameter get's answer during plans.
MAX_MEDIAN_OVERHEAD_S = 5e-3
MAX_PARAMETER_LATENCY_S = 0.02
#: The service is offered within this time (s) of the start, even on a first start's compile;
#: the first plan is answered within the first time (s), with a scene within the second.
MAX_START_S = 30.0
MAX_FIRST_ANSWER_S = (30.0, 90.0)
#: The node's peak resident memory (MB): without collision checking, with a scene.
MAX_PEAK_MB = (250.0, 400.0)
#: Liveness bound for a single answer or for the stream to be accounted for.
TIMEOUT_S = 120.0


def tool_goals(arm: ArmModel, count: int, seed: int) -> np.ndarray:
    """Tool positions of seeded random configurations inside the arm's limits."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(np.maximum(arm.lower, -np.pi), np.minimum(arm.upper, np.pi),
                    size=(count, arm.n_joints))
    q[:, arm.planned:] = 0.0
    goals = np.round(arm.tool(q)[0], 5)                   # 5 decimals: unique 6-digit log text
    if len({describe_goal(g) for g in goals}) != count:
        raise RuntimeError("goals collide in the node's log format; pick another --seed")
    return goals


def _pct(values: Sequence[float], q: float) -> float:
    return float(np.percentile(values, q))


def _ms(seconds: float) -> str:
    return f'{1e3 * seconds:.2f} ms'


def timed_call(ros: RosClient, client: Any, request: Any,
               timeout: float = TIMEOUT_S) -> tuple[Any | None, float]:
    """
    Call ``client``: (answer or None on timeout, round trip in s).

    The round trip runs from sending the request to the response callback, which runs in the
    client's executor thread as soon as the answer is in.
    """
    arrived: list[float] = []
    began = time.perf_counter()
    future = client.call_async(request)
    future.add_done_callback(lambda _: arrived.append(time.perf_counter()))
    try:
        answer = ros.result(future, timeout)
    except TimeoutError:
        return None, time.perf_counter() - began
    return answer, arrived[0] - began


def _in_process(arm: ArmModel, goals: np.ndarray) -> list[float]:
    """plan() times here, chaining starts as the node does."""
    prepare()
    start, times = np.clip(np.zeros(arm.n_joints), arm.lower, arm.upper), []   # as the node
    for goal in goals:
        result = plan(goal, start, arm=arm, seed=0)
        times.append(result.plan_time_s)
        if result.success:
            start = result.joint_goal
    return times


def _calls(node: PlannerProcess, ros: RosClient, client: Any, goals: np.ndarray,
           idle: bool) -> tuple[list[float], list[float], list[int]] | str:
    """
    Call plan_trajectory on each goal in turn.

    Return (round trips, logged plan times, poses in each answer), or the reason it failed.
    With ``idle``, each call waits until the node has
    logged the one before, its last step (publishing and logging follow the answer).
    """
    trips, sizes = [], []
    for i, goal in enumerate(goals):
        answer, trip = timed_call(ros, client, plan_request(tuple(goal)))
        if answer is None:
            return f'no answer within {TIMEOUT_S:.0f} s for goal {describe_goal(goal)}'
        trips.append(trip)
        sizes.append(len(answer.plan.poses))
        if idle or i == len(goals) - 1:
            logged = rf'service call #\d+ {re.escape(describe_goal(goal))} m from '
            node.wait_for(logged, timeout=TIMEOUT_S)
    logged = {m.group(1): float(m.group(2)) / 1e3 for m in node.matches(
        r'service call #\d+ (\([^)]*\)) m from .*; planned in ([0-9.]+) ms')}
    return trips, [logged[describe_goal(g)] for g in goals], sizes


def _service_phase(node: PlannerProcess, ros: RosClient, goals: np.ndarray,
                   more_goals: np.ndarray) -> tuple[bool, list[str]]:
    try:
        client = ros.client(GetPlan, 'plan_trajectory', TIMEOUT_S)
    except TimeoutError as exc:
        return False, [str(exc)]
    single = _calls(node, ros, client, goals, idle=True)
    if isinstance(single, str):
        return False, [single]
    trips, plans, sizes = single
    overhead = np.subtract(trips, plans)
    met = statistics.median(overhead) <= MAX_MEDIAN_OVERHEAD_S
    planned = np.flatnonzero(sizes)
    per_pose, fixed = np.polyfit(np.take(sizes, planned), overhead[planned], 1)
    lines = [
        f'service: {len(goals)} plan_trajectory calls, each to an idle node, {planned.size} '
        f'with a plan, {len(goals) - planned.size} empty (goal not reached)',
        f'  round trip (client)          median {_ms(statistics.median(trips))}, '
        f'p90 {_ms(_pct(trips, 90))}',
        f'  plan time (node, logged)     median {_ms(statistics.median(plans))}, '
        f'p90 {_ms(_pct(plans, 90))}',
        f'  overhead = round trip - plan median {_ms(statistics.median(overhead))}, '
        f'p90 {_ms(_pct(overhead, 90))}, max {_ms(max(overhead))} '
        f"(target: median <= {_ms(MAX_MEDIAN_OVERHEAD_S)}): {'met' if met else 'NOT MET'}",
        f'  path: median {statistics.median(np.take(sizes, planned)):g} poses (range '
        f'{min(np.take(sizes, planned))}..{max(sizes)}, one per sample period of motion); '
        f'overhead ~ {_ms(fixed)} + {1e6 * per_pose:.1f} us per pose (least squares)',
    ]
    burst = _calls(node, ros, client, more_goals, idle=False)
    if isinstance(burst, str):
        return False, lines + [burst]
    trips, plans, _ = burst
    overhead = np.subtract(trips, plans)
    lines.append(
        f'  back to back ({len(more_goals)} more calls, each sent when the last answer arrives, '
        f'so it also waits while the node publishes and logs the last plan): overhead median '
        f'{_ms(statistics.median(overhead))}, p90 {_ms(_pct(overhead, 90))}')
    return met, lines


def _missing(goals: np.ndarray, settled: dict[str, str]) -> str:
    """List the goals (numbered from 1 in sending order) neither planned nor dropped."""
    lost = [f'#{i} {describe_goal(g)}' for i, g in enumerate(goals, 1)
            if describe_goal(g) not in settled]
    return f" ({', '.join(lost[:5])}{', ...' if len(lost) > 5 else ''})" if lost else ''


def _warm_up(node: PlannerProcess, ros: RosClient, publisher: Any, params: Any) -> None:
    """
    Publish refused goals until the node has logged one.

    Until then the two sides may not have matched each other yet, and a first sample could be
    lost.
    """
    deadline = time.monotonic() + TIMEOUT_S
    nan = float('nan')
    warmed = r'\]: goal #\d+ \(nan, nan, nan\) m from '
    while not node.matches(warmed) and time.monotonic() < deadline:
        publisher.publish(Point(x=nan, y=nan, z=nan))
        timed_call(ros, params, GetParameters.Request(names=['angular_velocity']))
        threading.Event().wait(0.05)


def _settle(node: PlannerProcess, goals: np.ndarray) -> dict[str, str]:
    """Wait until every goal is logged as planned or dropped (or time out): how each went."""
    wanted = {describe_goal(g) for g in goals}
    settled: dict[str, str] = {}

    def accounted() -> bool:
        for m in node.matches(r'\]: goal #\d+ (\([^)]*\)) m from '):
            settled.setdefault(m.group(1), 'planned')
        for m in node.matches(r'\]: superseded goal #\d+ (\([^)]*\)) m: '):
            settled.setdefault(m.group(1), 'dropped')
        return wanted <= settled.keys()

    deadline = time.monotonic() + TIMEOUT_S
    while not accounted() and time.monotonic() < deadline:
        threading.Event().wait(0.05)
    return settled


def _stream_report(node: PlannerProcess, goals: np.ndarray, settled: dict[str, str],
                   latencies: list[float], rate: float, sent: float) -> tuple[bool, list[str]]:
    """Judge the goal stream: every goal accounted for, every parameter get prompt."""
    wanted = {describe_goal(g) for g in goals}
    planned = sum(1 for g in wanted if settled.get(g) == 'planned')
    dropped = sum(1 for g in wanted if settled.get(g) == 'dropped')
    missing = len(wanted) - planned - dropped
    published = len([m for m in node.matches(r'\]: goal #\d+ (\([^)]*\)) m from .*; published')
                     if m.group(1) in wanted])
    worst = max(latencies)
    all_met = missing == 0 and worst <= MAX_PARAMETER_LATENCY_S
    lines = [
        f'goal stream: {len(goals)} goals on goal at {rate:g} Hz (sent in {sent:.2f} s)',
        f'  planned {planned} ({published} reached and published), dropped {dropped} (each '
        f'logged), unaccounted {missing}{_missing(goals, settled)}: '
        f"{'met' if missing == 0 else 'NOT MET'}",
        f'  parameter get every 10 ms meanwhile: {len(latencies)} sent, '
        f'{sum(np.isfinite(latencies))} answered, median '
        f'{_ms(statistics.median(latencies))}, p99 {_ms(_pct(latencies, 99))}, max {_ms(worst)} '
        f'(target: max <= {_ms(MAX_PARAMETER_LATENCY_S)}): '
        f"{'met' if worst <= MAX_PARAMETER_LATENCY_S else 'NOT MET'}",
    ]
    return all_met, lines


def _stream_phase(node: PlannerProcess, ros: RosClient, goals: np.ndarray,
                  rate: float) -> tuple[bool, list[str]]:
    """Publish ``goals`` at ``rate`` Hz while a parameter get goes out every 10 ms."""
    # a history as deep as the stream: a reliable writer drops its oldest unacknowledged sample
    # when a shorter history is full
    publisher = ros.node.create_publisher(Point, 'goal', len(goals))
    try:
        params = ros.client(GetParameters, 'trajplan/get_parameters', TIMEOUT_S)
    except TimeoutError as exc:
        return False, [str(exc)]
    _warm_up(node, ros, publisher, params)
    latencies: list[float] = []
    stop = threading.Event()

    def poll_parameters() -> None:
        request = GetParameters.Request(names=['angular_velocity'])
        while not stop.is_set():
            answer, trip = timed_call(ros, params, request)
            latencies.append(trip if answer is not None else float('inf'))
            stop.wait(0.01)

    poller = threading.Thread(target=poll_parameters, daemon=True)
    poller.start()
    began = time.perf_counter()
    for i, goal in enumerate(goals):
        publisher.publish(Point(x=float(goal[0]), y=float(goal[1]), z=float(goal[2])))
        time.sleep(max(0.0, began + (i + 1) / rate - time.perf_counter()))   # the goal rate
    sent = time.perf_counter() - began
    settled = _settle(node, goals)
    stop.set()
    poller.join(timeout=TIMEOUT_S)
    return _stream_report(node, goals, settled, latencies, rate, sent)


def _start_phase(node: PlannerProcess, ros: RosClient, began: float, goal: np.ndarray,
                 scene: bool) -> bool:
    """
    Print when the service was offered, the first plan answered and the node ready.

    The first call goes to ``compute_plan`` (never published: the node's start stays). True
    when every target is met.
    """
    offered = time.perf_counter() - began
    first, _ = timed_call(ros, ros.client(GetPlan, 'compute_plan'), plan_request(tuple(goal)),
                          COMPILE_BOUND_S)
    answered = time.perf_counter() - began
    ready = node.wait_for(r'\]: ready: ', COMPILE_BOUND_S)
    kernels = node.wait_for(r'\]: ((?:compiled|loaded) .*planning kernels in .*)$', 0.0)
    most = MAX_FIRST_ANSWER_S[scene]
    print(f'start-up: service offered {offered:.2f} s after the start (target: '
          f'{MAX_START_S:g} s); first plan answered after {answered:.2f} s (target: '
          f'{most:g} s); ready to plan after {time.perf_counter() - began:.2f} s'
          if ready and first else 'start-up: the node did not get ready',
          f'({kernels.group(1)})' if kernels else '')
    return bool(ready and first) and offered <= MAX_START_S and answered <= most


def description_args(args: argparse.Namespace, folder: str) -> list[str]:
    """
    Return the node's --ros-args for ``--urdf`` and ``--scene``.

    A parameters file with the description; the collision check with the scene file.
    """
    scene = (['-p', 'collision_check:=true', '-p',
              f'scene_file:={Path(args.scene).resolve()}'] if args.scene else [])
    if not args.urdf:
        return scene
    params = Path(folder) / 'description.yaml'           # JSON is YAML
    params.write_text(json.dumps({'/**': {'ros__parameters': {
        'robot_description': Path(args.urdf).read_text(encoding='utf-8'),
        'tip_link': args.tip_link or ''}}}), encoding='utf-8')
    return ['--params-file', str(params), *scene]


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog='python -m trajplan_ros.tools.bench_node',
                                     description=__doc__.split('\n\n')[0])
    parser.add_argument('--calls', type=int, default=100, help='service calls (default 100)')
    parser.add_argument('--goals', type=int, default=200, help='streamed goals (default 200)')
    parser.add_argument('--rate', type=float, default=100.0, help='goal rate, Hz (default 100)')
    parser.add_argument('--seed', type=int, default=3, help='seed of the goals (default 3)')
    parser.add_argument('--urdf', metavar='FILE',
                        help="plan for this URDF's chain (given to the node as its "
                             'robot_description; default: the paper arm)')
    parser.add_argument('--tip-link', metavar='NAME', help="the chain's tip link, with --urdf")
    parser.add_argument('--scene', metavar='FILE',
                        help='check collisions among the obstacles of this scene file')
    args = parser.parse_args(argv)

    arm = (ArmModel.from_urdf(args.urdf, None, args.tip_link) if args.urdf else paper_arm())
    call_goals = tool_goals(arm, args.calls, args.seed)
    burst_goals = tool_goals(arm, args.calls, args.seed + 1)
    stream_goals = tool_goals(arm, args.goals, args.seed + 2)
    env = ros_environment()
    os.environ.update(env)
    print(f'planner_node benchmark: python -m trajplan_ros.tools.bench_node '
          f"{' '.join(argv if argv is not None else sys.argv[1:])}".rstrip())
    print(f'machine: {platform.machine()}, {os.cpu_count()} CPUs, Python '
          f'{platform.python_version()}, {get_rmw_implementation_identifier()}')
    folder = tempfile.TemporaryDirectory(prefix='trajplan-bench-node-')
    began = time.perf_counter()
    node = PlannerProcess(description_args(args, folder.name), env=env)
    ros = RosClient('trajplan_bench')
    try:
        ros.client(GetPlan, 'plan_trajectory')
        met_start = _start_phase(node, ros, began, stream_goals[0], bool(args.scene))
        here = _in_process(arm, call_goals)         # after the start: it may share a cache
        met_service, service_lines = _service_phase(node, ros, call_goals, burst_goals)
        print('\n'.join(service_lines[:5]))
        print(f'  plan() in this process on the same goals from the same starts: median '
              f'{_ms(statistics.median(here))}, p90 {_ms(_pct(here, 90))}')
        print('\n'.join(service_lines[5:]))
        met_stream, stream_lines = _stream_phase(node, ros, stream_goals, args.rate)
        print('\n'.join(stream_lines))
        peak, bound = rss_mb(node.pid, 'VmHWM'), MAX_PEAK_MB[bool(args.scene)]
        print(f'memory: peak RSS {peak:.0f} MB (target: {bound:g} MB '
              f"{'with a scene' if args.scene else 'without collision checking'})")
        met_stream = met_stream and peak <= bound
    finally:
        ros.close()
        code = node.stop()
        folder.cleanup()
    if code != 0 or any('Traceback' in line for line in node.lines):
        print(f'planner_node exited with {code}:\n' + '\n'.join(node.lines[-20:]))
        return 1
    return 0 if met_start and met_service and met_stream else 1


if __name__ == '__main__':
    sys.exit(main())
