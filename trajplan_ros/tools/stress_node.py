# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Stress benchmark of the planner node over DDS: ``python -m trajplan_ros.tools.stress_node``.

Each probe runs the node as a child process (a DDS domain of its own, localhost discovery) and
talks to it the way other ROS 2 processes would:

1. burst: ``--clients`` client nodes each send ``--calls`` plan_trajectory calls at once;
   every call must be answered exactly once; a parameter get every 10 ms meanwhile.
2. flood: ``--goals`` goals at ``--rate`` Hz from a reliable KEEP_ALL publisher; every goal
   must be accounted for in the log and in diagnostics (planned + superseded + failed =
   received = sent); a parameter get every 10 ms meanwhile (p99 <= 50 ms, max <= 100 ms).
   The parameter gets come from a process of their own, as from any other ROS tool.
3. shutdown: SIGINT with ``--queued`` calls waiting behind a long plan; every call answered,
   exit code 0, no traceback (the time to exit is printed).
4. extremes: the most extreme parameters the descriptors allow; no plan over
   max_trajectory_points, peak RSS under 250 MB.
5. fuzz: ``--fuzz`` malformed goals and joint_states (NaN, inf, +-1e308, denormals, mismatched
   lengths, duplicate names); the node lives, plans the paper's target correctly afterwards,
   RSS grows by less than 50 MB.
6. sequence: ``--sequence`` calls one after another; RSS grows by less than 20 MB between call
   100 and the last.

Prints the figures and exits 0 when every target is met, 1 otherwise.
"""
from __future__ import annotations

import argparse
import gc
import json
import math
import os
import re
import signal
import subprocess
import sys
import threading
import time
from typing import Any, Callable, Sequence

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Point
from nav_msgs.srv import GetPlan
import numpy as np
from rcl_interfaces.srv import GetParameters
from rclpy.duration import Duration
from sensor_msgs.msg import JointState
from trajplan_ros.kinematics import paper_arm
from trajplan_ros.planning import plan
from trajplan_ros.planning.planner import describe_goal
from trajplan_ros.tools.bench.cases import PAPER_TARGET
from trajplan_ros.tools.node_process import (COMPILE_BOUND_S, PlannerProcess, ros_environment,
                                             rss_mb, TIMEOUT_S, wait_until)
from trajplan_ros.tools.ros_client import KEEP_ALL, plan_request, RosClient


__all__ = ['main']

HOPELESS_GOAL = (0.05, -0.05, -0.25)        # inside the reach sphere, never reached
Result = tuple[bool, list[str]]


def _goals(count: int, seed: int) -> list[tuple[float, float, float]]:
    """Tool positions of seeded random in-limit configurations, unique in the log's format."""
    arm = paper_arm()
    q = np.random.default_rng(seed).uniform(arm.lower, arm.upper, (count, arm.n_joints))
    out = [tuple(float(v) for v in np.round(p, 5)) for p in arm.tool(q)[0]]
    if len({describe_goal(g) for g in out}) != count:
        raise RuntimeError('goals collide in the node log format; pick another --seed')
    return out


class _ParameterPoller:
    """
    A parameter get every 10 ms from a process of its own; round trips in s (inf: no answer).

    A process of its own, like any other ROS tool asking the node: this process's own pauses
    (rclpy calls that block holding the interpreter lock, such as ``wait_for_all_acked``, new
    and closed clients, reading the node's log) stay out of the figures.
    """

    def __init__(self, node_name: str, env: dict[str, str]) -> None:
        self._proc = subprocess.Popen(
            [sys.executable, '-m', 'trajplan_ros.tools.stress_node', '--poll', node_name],
            env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        assert self._proc.stdout is not None
        if self._proc.stdout.readline().strip() != 'polling':     # once the service is found
            self._proc.kill()
            self._proc.wait()
            raise RuntimeError(f'the parameter poller did not start on {node_name}')

    def finish(self) -> tuple[bool, str]:
        """Stop polling; judge p99 <= 50 ms and max <= 100 ms."""
        try:
            out, _ = self._proc.communicate('', timeout=TIMEOUT_S)    # end of input: stop
            latencies = [float(v) for v in json.loads(out or '[]')]
        except subprocess.TimeoutExpired:
            self._proc.kill()
            self._proc.wait()
            latencies = []
        lat = np.array(latencies or [np.inf])
        p99, worst = float(np.percentile(lat, 99)), float(lat.max())
        met = p99 <= 0.05 and worst <= 0.1
        return met, (f'parameter get every 10 ms: {lat.size} sent, median '
                     f'{1e3 * np.median(lat):.1f} ms, p99 {1e3 * p99:.1f} ms, max '
                     f'{1e3 * worst:.1f} ms (target p99 <= 50, max <= 100): '
                     f"{'met' if met else 'NOT MET'}")


def poll(node_name: str) -> int:
    """Get a parameter every 10 ms until standard input ends; print the round trips (JSON)."""
    ros = RosClient('stress_poller')
    try:
        client = ros.client(GetParameters, f'{node_name}/get_parameters')
        request = GetParameters.Request(names=['angular_velocity'])
        gc.freeze()         # no full collection (0.1-0.4 s under load) walks the imports
        ended = threading.Event()
        threading.Thread(target=lambda: (sys.stdin.read(), ended.set()), daemon=True).start()
        print('polling', flush=True)
        latencies: list[float] = []
        while not ended.is_set():
            began = time.perf_counter()
            try:
                ros.result(client.call_async(request), 5.0)
                latencies.append(time.perf_counter() - began)
            except TimeoutError:
                latencies.append(float('inf'))
            ended.wait(0.01)
    finally:
        ros.close()
    print(json.dumps([v if math.isfinite(v) else 'inf' for v in latencies]), flush=True)
    return 0


def _start(env: dict[str, str], *ros_args: str) -> PlannerProcess:
    node = PlannerProcess(['--log-level', 'trajplan:=debug', *ros_args], env=env)
    if node.wait_for(r'\]: ready: ', COMPILE_BOUND_S) is None:     # a first start compiles
        node.stop()
        raise RuntimeError('the node did not start:\n' + '\n'.join(node.lines[-20:]))
    return node


def _polling(node: PlannerProcess, env: dict[str, str],
             clients: Sequence[RosClient]) -> _ParameterPoller:
    """Start polling the node's parameters; close ``clients`` and stop the node on failure."""
    try:
        return _ParameterPoller('/trajplan', env)
    except BaseException:
        for client in clients:
            client.close()
        node.stop()
        raise


def _verdict(met: bool) -> str:
    return 'met' if met else 'NOT MET'


def burst(env: dict[str, str], clients: int, calls: int) -> Result:
    """Probe 1: ``clients`` x ``calls`` concurrent calls, each answered exactly once."""
    node = _start(env)
    # the clients first: discovering a new participant pauses the node for about 0.1 s (DDS
    # calls that hold the interpreter lock meanwhile), which is not what the polling measures
    callers = [RosClient(f'stress_caller{k}') for k in range(clients)]
    poller = _polling(node, env, callers)
    try:
        asked = [_goals(calls, seed=100 + k) for k in range(clients)]
        # one call each first, answered: a client that has just seen the service may not be
        # matched with it yet, and requests written before the match are lost (DDS discovery,
        # before the node), which is not what this probe measures
        for caller, goals in zip(callers, asked):
            caller.call(GetPlan, 'plan_trajectory', plan_request(goals[0]))
        futures = [[c.call_async(GetPlan, 'plan_trajectory', plan_request(g)) for g in goals]
                   for c, goals in zip(callers, asked)]
        answers = sum(1 for c, fs in zip(callers, futures) for f in fs
                      if c.result(f, TIMEOUT_S) is not None)
    finally:
        for caller in callers:
            caller.close()
        latency_met, latency = poller.finish()
        node.stop()
    logged = [int(m.group(1)) for m in node.matches(r'\]: service call #(\d+) \(')]
    total = clients * calls
    once = sorted(logged) == list(range(1, total + clients + 1))          # with the first calls
    met = answers == total and once and latency_met
    return met, [f'burst: {clients} clients x {calls} concurrent calls: {answers} of {total} '
                 f"answered, {'each planned once' if once else 'NOT each planned once'}: "
                 f'{_verdict(answers == total and once)}', '  ' + latency]


def flood(env: dict[str, str], count: int, rate: float) -> Result:
    """Probe 2: ``count`` goals at ``rate`` Hz, every one accounted for."""
    node = _start(env)
    ros = RosClient('stress_flood')                 # before polling, as in ``burst``
    poller = _polling(node, env, [ros])
    try:
        publisher = ros.node.create_publisher(Point, 'goal', KEEP_ALL)
        wait_until(lambda: publisher.get_subscription_count() > 0, what='the goal subscriber')
        sent = _goals(count, seed=200)
        # the first goal alone, until the node has it: this publisher sees the node's reader
        # before that reader has matched it, and what it writes meanwhile never arrives (DDS
        # discovery, before the node), which is not what this probe measures
        publisher.publish(Point(x=sent[0][0], y=sent[0][1], z=sent[0][2]))
        node.wait_for(rf'\]: queued goal #1 {re.escape(describe_goal(sent[0]))} ', TIMEOUT_S)
        began = time.perf_counter()
        for i, g in enumerate(sent[1:]):
            publisher.publish(Point(x=g[0], y=g[1], z=g[2]))
            time.sleep(max(0.0, began + (i + 1) / rate - time.perf_counter()))   # the rate
        seconds = time.perf_counter() - began
        settled = _settle(node, sent)
        counted = _wait_for_diagnostics(ros, _balanced(count),
                                        'diagnostics accounting for every goal')
    finally:
        ros.close()
        latency_met, latency = poller.finish()
        node.stop()
    kinds = {k: list(settled.values()).count(k) for k in ('planned', 'superseded', 'failed')}
    accounted = sum(kinds.values())
    met = accounted == count and counted and latency_met
    return met, [f'flood: {count} goals at {rate:g} Hz (sent in {seconds:.2f} s): '
                 f"{accounted} accounted for in the log ({kinds['planned']} planned, "
                 f"{kinds['superseded']} superseded, {kinds['failed']} failed), "
                 f"{'and in diagnostics' if counted else 'NOT in diagnostics'}: "
                 f'{_verdict(accounted == count and counted)}', '  ' + latency]


def _wait_for_diagnostics(ros: RosClient, holds: Callable[[dict[str, str]], bool],
                          what: str) -> bool:
    """Wait until a status on /diagnostics has values (key -> text) for which ``holds``."""
    box = ros.inbox(DiagnosticArray, '/diagnostics')

    def reported() -> bool:
        while not box.empty():
            for status in box.get().status:
                if holds({kv.key: kv.value for kv in status.values}):
                    return True
        return False

    try:
        wait_until(reported, TIMEOUT_S, what)
    except TimeoutError:
        return False
    return True


def _balanced(count: int) -> Callable[[dict[str, str]], bool]:
    """Diagnostics say received = planned + superseded + failed = ``count``."""
    ends = ('goals_planned', 'goals_superseded', 'goals_failed')
    return lambda v: (v.get('goals_received') == str(count)
                      and sum(int(v[k]) for k in ends) == count)


def _settle(node: PlannerProcess, sent: list[tuple[float, float, float]]) -> dict[str, str]:
    """Wait until the log accounts for every goal; return how each ended."""
    wanted = {describe_goal(g) for g in sent}
    settled: dict[str, str] = {}
    patterns = (('planned', r'\]: goal #\d+ (\([^)]*\)) m from .*; published '),
                ('failed', r'\]: goal #\d+ (\([^)]*\)) m from .*: (?:rejected|not_reached|'
                           r'timed_out|cancelled|refused)'),
                ('superseded', r'\]: superseded goal #\d+ (\([^)]*\)) m: '),
                ('failed', r'\]: goal #\d+ (\([^)]*\)) m: (?:unplanned|planning failed)'))

    def accounted() -> bool:
        for kind, pattern in patterns:
            for m in node.matches(pattern):
                settled.setdefault(m.group(1), kind)
        return wanted <= settled.keys()

    try:
        wait_until(accounted, TIMEOUT_S, 'every goal in the log')
    except TimeoutError:
        pass
    return {g: k for g, k in settled.items() if g in wanted}


def shutdown(env: dict[str, str], queued: int) -> Result:
    """Probe 3: SIGINT with ``queued`` calls waiting behind a long plan."""
    node = _start(env, '-p', 'algorithm:=pso', '-p', 'population:=5000',
                  '-p', 'max_iterations:=1000000', '-p', 'max_planning_time:=60.0')
    ros = RosClient('stress_shutdown')
    try:
        first = ros.call_async(GetPlan, 'plan_trajectory', plan_request(HOPELESS_GOAL))
        node.wait_for(r'planning service call #1 ', TIMEOUT_S)
        rest = [ros.call_async(GetPlan, 'plan_trajectory', plan_request(g))
                for g in _goals(queued, seed=300)]
        if not _wait_for_diagnostics(ros, lambda v: v.get('calls_waiting') == str(queued),
                                     f'{queued} calls waiting'):
            raise TimeoutError(f'the node never had {queued} calls waiting')
        node.proc.send_signal(signal.SIGINT)
        began = time.monotonic()
        code = node.proc.wait(timeout=TIMEOUT_S)
        took = time.monotonic() - began
        answered = sum(1 for f in rest if _answered(ros, f))
    finally:
        ros.close()
        node.stop()
    clean = code == 0 and not any('Traceback' in line for line in node.lines)
    met = answered == queued and clean and took <= 2.0
    first_done = 'answered' if first.done() else 'NOT answered'
    return met, [f'shutdown: SIGINT with {queued} calls queued behind a running plan: '
                 f'{answered} of {queued} answered (the running one {first_done}), exit code '
                 f'{code} after {took:.2f} s (target 2 s), '
                 f"{'no traceback' if clean else 'TRACEBACK or bad exit'}: {_verdict(met)}"]


def _answered(ros: RosClient, future: Any) -> bool:
    try:
        return ros.result(future, 5.0) is not None
    except TimeoutError:
        return False


def extremes(env: dict[str, str]) -> Result:
    """Probe 4: the most extreme parameters the descriptors allow."""
    node = _start(env, '-p', 'angular_velocity:=0.001', '-p', 'sample_period:=0.001',
                  '-p', 'max_trajectory_points:=50000', '-p', 'population:=10000',
                  '-p', 'max_iterations:=1000000', '-p', 'max_planning_time:=60.0',
                  '-p', 'mode:=radial')
    ros = RosClient('stress_extremes')
    try:
        for goal in [(0.2, 0.1, 0.15), tuple(PAPER_TARGET.tolist()), (0.01, 0.0, 0.36)]:
            ros.call(GetPlan, 'plan_trajectory', plan_request(goal), TIMEOUT_S + 30)
        peak = rss_mb(node.pid, 'VmHWM')
    finally:
        ros.close()
        node.stop()
    points = [int(m.group(1)) for m in node.matches(r'published (\d+) points')]
    refused = len(node.matches(r'refused: the trajectory would need'))
    met = all(n <= 50000 for n in points) and peak < 250
    return met, [f'extremes: angular_velocity 0.001, sample_period 0.001, population 10000, '
                 f'max_trajectory_points 50000, radial: {len(points)} published (largest '
                 f'{max(points, default=0)} points), {refused} refused over the bound, peak '
                 f'RSS {peak:.0f} MB (target < 250 MB): {_verdict(met)}']


def _fuzz_messages(count: int, seed: int) -> list[tuple[str, Any]]:
    rng = np.random.default_rng(seed)
    odd = [float('nan'), float('inf'), -float('inf'), 1e308, -1e308, 5e-324, -5e-324, 0.0]
    names = ['joint1', 'joint2', 'joint3', 'joint4', 'joint5']
    out: list[tuple[str, Any]] = []
    for k in range(count):
        if k % 2:
            out.append(('goal', Point(x=float(rng.choice(odd)), y=float(rng.choice(odd)),
                                      z=float(rng.choice(odd)))))
            continue
        picked = list(rng.choice(names + ['joint1', 'Joint1'], size=rng.integers(0, 7)))
        positions = [float(rng.choice(odd)) for _ in range(len(picked) + rng.integers(-1, 2))]
        out.append(('joint_states', JointState(name=picked, position=positions)))
    return out


def _restore_state(node: PlannerProcess, ros: RosClient, states: Any) -> None:
    """Publish q = 0 on joint_states until a plan's log line starts from it."""
    zero = JointState(name=list(paper_arm().joint_names), position=[0.0] * 5)

    def restored() -> bool:
        states.publish(zero)
        mark = len(node.lines)
        ros.call(GetPlan, 'plan_trajectory', plan_request((float('nan'), 0.0, 0.0)))
        line = node.wait_for(r'\(nan, 0, 0\) m from q = \(([^)]*)\)', TIMEOUT_S, mark)
        return line is not None and line.group(1) == '0, 0, 0, 0, 0'

    wait_until(restored, TIMEOUT_S, 'a valid joint state')


def fuzz(env: dict[str, str], count: int) -> Result:
    """Probe 5: malformed goals and joint_states; the node lives and still plans right."""
    node = _start(env)
    ros = RosClient('stress_fuzz')
    target = tuple(PAPER_TARGET.tolist())
    try:
        before = rss_mb(node.pid)
        publishers = {'goal': ros.publisher(Point, 'goal'),
                      'joint_states': ros.publisher(JointState, 'joint_states')}
        for topic, msg in _fuzz_messages(count, seed=400):
            publishers[topic].publish(msg)
        publishers['goal'].wait_for_all_acked(Duration(seconds=TIMEOUT_S))
        # a fuzzed state can be finite and far outside the limits: then the arm really is there
        # and plans are refused; the robot's next valid state must set things right
        _restore_state(node, ros, publishers['joint_states'])
        answer = ros.call(GetPlan, 'plan_trajectory', plan_request(target))
        logged = node.wait_for(r'service call #\d+ \(0.151171, 0.19162, 0.172124\) m from q = '
                               r'\(([^)]*)\) rad.*: (reached in \S+ s)', TIMEOUT_S)
        grown = rss_mb(node.pid) - before
    finally:
        ros.close()
        node.stop()
    right = False
    if logged and answer.plan.poses:
        start = np.array([float(v) for v in logged.group(1).split(',')])
        expected = plan(PAPER_TARGET, start, seed=0)       # the log's start has 6 digits
        last = answer.plan.poses[-1].pose.position
        right = (np.linalg.norm(np.subtract([last.x, last.y, last.z], target)) <= 1e-6
                 and abs(float(logged.group(2).split()[2]) - expected.motion_time_s) <= 1e-4)
    clean = not any('Traceback' in line for line in node.lines)
    met = right and clean and grown < 50
    return met, [f'fuzz: {count} malformed goals and joint_states: alive, paper target '
                 f"{'planned right' if right else 'NOT planned right'} afterwards, "
                 f"{'no traceback' if clean else 'TRACEBACK'}, RSS growth {grown:.1f} MB "
                 f'(target < 50 MB): {_verdict(met)}']


def sequence(env: dict[str, str], count: int) -> Result:
    """Probe 6: ``count`` calls in sequence; RSS growth between call 100 and the last."""
    node = _start(env)
    ros = RosClient('stress_sequence')
    rss = {}
    try:
        for k, goal in enumerate(_goals(count, seed=500), start=1):
            ros.call(GetPlan, 'plan_trajectory', plan_request(goal))
            if k in (100, count):
                rss[k] = rss_mb(node.pid)
    finally:
        ros.close()
        node.stop()
    grown = rss[count] - rss[100]
    met = grown < 20
    return met, [f'sequence: {count} calls one after another: RSS {rss[100]:.1f} MB at call '
                 f'100, {rss[count]:.1f} MB at call {count}, growth {grown:.1f} MB (target < '
                 f'20 MB): {_verdict(met)}']


def main(argv: Sequence[str] | None = None) -> int:
    """Run the probes; print the figures; exit 0 when every target is met."""
    parser = argparse.ArgumentParser(prog='python -m trajplan_ros.tools.stress_node',
                                     description=__doc__.split('\n\n')[0].strip())
    parser.add_argument('--clients', type=int, default=4)
    parser.add_argument('--calls', type=int, default=50, help='calls per client')
    parser.add_argument('--goals', type=int, default=600)
    parser.add_argument('--rate', type=float, default=200.0, help='goal rate, Hz')
    parser.add_argument('--queued', type=int, default=20)
    parser.add_argument('--fuzz', type=int, default=500)
    parser.add_argument('--sequence', type=int, default=1000)
    parser.add_argument('--probes', default='burst,flood,shutdown,extremes,fuzz,sequence',
                        help='comma-separated probes to run (default: all)')
    parser.add_argument('--poll', metavar='NODE', help=argparse.SUPPRESS)   # the poller's own
    args = parser.parse_args(argv)
    if args.poll:
        return poll(args.poll)
    env = ros_environment()
    os.environ.update(env)
    probes: dict[str, Callable[[], Result]] = {
        'burst': lambda: burst(env, args.clients, args.calls),
        'flood': lambda: flood(env, args.goals, args.rate),
        'shutdown': lambda: shutdown(env, args.queued),
        'extremes': lambda: extremes(env),
        'fuzz': lambda: fuzz(env, args.fuzz),
        'sequence': lambda: sequence(env, args.sequence),
    }
    print('planner_node stress benchmark: python -m trajplan_ros.tools.stress_node '
          + ' '.join(argv if argv is not None else sys.argv[1:]))
    all_met = True
    for name in args.probes.split(','):
        met, lines = probes[name.strip()]()
        all_met &= met
        print('\n'.join(lines), flush=True)
    return 0 if all_met else 1


if __name__ == '__main__':
    sys.exit(main())
