# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The ``trajplan bench-detours`` subcommand: motions around obstacles, beside OMPL's RRTConnect.

Scenes and goals are bench-collisions' (``draw_scene``, ``draw_goal``), with a fresh seed. Each
goal is planned with the scene and ``detours`` off. Where that plan ends ``not_reached`` because
every direct motion found collides (a blocked goal), it is planned again with detours, and:

* the goal's joint solutions (``--brute`` random joint vectors projected onto it and polished)
  whose own pose keeps the padding are the joint goals OMPL is given (``ompl_peer``: RRTConnect
  with this package's continuous check as the motion validator, then its path simplification,
  timed segment by segment with the same law); the brute force also checks their direct motions,
  to count blocked goals that had a free direct motion after all;
* a goal is reachable where either planner found a free motion: OMPL with ``--ompl-time``
  seconds is the judge the targets ask for, and a detour checked free proves it too;
* both answers are sampled every millisecond and checked by python-fcl on the real shapes.

Goals with a free direct motion are planned with detours on as well: the answer must be the
same, at the same plan time. The report gives, per arm: blocked goals, reachable ones, those
planned and the collisions; on the goals both solve, how often the detour is no slower than
OMPL's path, the median ratio of their durations, and the plan times; the detour's plan time
against the same goal's plan with detours off.

``--rows FILE`` also writes every goal's measurements, one JSON object a line.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass, field
import time

import numpy as np
from trajplan_ros.collision.distances import CollisionWorld
from trajplan_ros.collision.free_motion import check_motion, START_TOLERANCE, StartLimits
from trajplan_ros.motion.trajectory import path_trajectory
from trajplan_ros.planning.planner import plan, PlanRequest, PlanResult, PlanStatus, prepare
from trajplan_ros.search.free_goal import distinct_goals
from trajplan_ros.tools.bench import ompl_peer
from trajplan_ros.tools.bench.clearance import IndependentCheck
from trajplan_ros.tools.bench.collision_bench import (add_scene_arguments, bench_seed,
                                                      BenchArm, every_millisecond,
                                                      goal_solutions, measure_scenes)

__all__ = ['add_parser']


@dataclass
class Row:
    """One goal's measurements (times in s; None: not planned or not found)."""

    arm: str
    scene: int
    seed: int
    goal: list[float]
    direct_status: str
    direct_time: float                   # plan time with detours off
    blocked: bool = False                # every direct motion found collides
    same_with_detours: bool | None = None     # free direct goals: the same answer with detours
    time_with_detours: float | None = None
    detour_motion: float | None = None
    detour_vias: int = 0
    detour_broken: list[str] = field(default_factory=list)
    clear_goals: int = 0                 # joint solutions whose own pose keeps the padding
    brute_direct: float | None = None    # a free direct motion the brute force found
    ompl_motion: float | None = None
    ompl_time: float | None = None
    ompl_waypoints: int = 0
    ompl_broken: list[str] = field(default_factory=list)


def _blocked(row: Row, bench: BenchArm, world: CollisionWorld, check: IndependentCheck,
             request: PlanRequest, args: argparse.Namespace) -> None:
    """Plan a blocked goal with detours and with OMPL; check both by python-fcl."""
    clock = time.perf_counter()
    around = plan(request)
    row.time_with_detours = time.perf_counter() - clock
    if around.success:
        row.detour_motion, row.detour_vias = around.motion_time_s, len(around.via_points)
        row.detour_broken = check.violations(
            every_millisecond(around.trajectory(sample_period=1.0)), START_TOLERANCE)
    obj, solutions = goal_solutions(bench, request.goal.position, request.angular_velocity,
                                    args.brute)
    law, timing = around.law, around.motion.timing
    limits = StartLimits.at(world, bench.start)

    def free(a: np.ndarray, b: np.ndarray) -> bool:
        return check_motion(world, a, b, law, timing, False, limits).free

    clear = [x for x in distinct_goals(solutions) if free(obj.full(x)[0], obj.full(x)[0])]
    row.clear_goals = len(clear)
    direct = [x for x in clear if free(bench.start, obj.full(x)[0])]
    if direct:
        row.brute_direct = float(obj.motion_time(direct[0][None])[0])
    if not clear:
        return
    peer = ompl_peer.rrt_connect(obj, world, law, timing, np.array(clear), args.ompl_time,
                                 args.ompl_simplify)
    if peer is not None:
        row.ompl_motion, row.ompl_time = peer.duration, peer.plan_time
        row.ompl_waypoints = len(peer.points)
        path = path_trajectory(peer.points, law, timing, sample_period=1.0)
        row.ompl_broken = check.violations(every_millisecond(path), START_TOLERANCE)


def _measure(bench: BenchArm, world: CollisionWorld, check: IndependentCheck,
             goal: np.ndarray, args: argparse.Namespace, seed: int, scene: int) -> Row:
    """Plan one goal with detours off; then as a blocked goal, or again with detours on."""
    request = PlanRequest(goal, bench.start, arm=bench.arm, seed=seed,
                          angular_velocity=args.angular_velocity, world=world)
    clock = time.perf_counter()
    direct = plan(request.replace(detours=False))
    row = Row(bench.name, scene, seed, goal.tolist(), direct.status.value,
              time.perf_counter() - clock)
    if direct.status is PlanStatus.NOT_REACHED and direct.message.startswith('every direct'):
        row.blocked = True
        _blocked(row, bench, world, check, request, args)
    elif direct.success:
        clock = time.perf_counter()
        again: PlanResult = plan(request)
        row.time_with_detours = time.perf_counter() - clock
        row.same_with_detours = bool(np.array_equal(again.joint_goal, direct.joint_goal)
                                     and not again.via_points)
    return row


def _median(values: list[float]) -> float:
    return float(np.median(values)) if values else float('nan')


def _arm_lines(mine: list[Row]) -> tuple[str, str, str]:
    """Return one arm's line of each table: blocked goals, against OMPL, free direct goals."""
    blocked = [r for r in mine if r.blocked]
    reachable = [r for r in blocked if r.ompl_motion is not None or r.detour_motion is not None]
    planned = [r for r in blocked if r.detour_motion is not None]
    hits = sum(bool(r.detour_broken) for r in planned)
    peer_hits = sum(bool(r.ompl_broken) for r in blocked)
    missed = sum(r.brute_direct is not None for r in blocked)
    share = 100 * len(planned) / len(reachable) if reachable else float('nan')
    first = (f'{len(mine):5}  {len(blocked):7}  {sum(r.clear_goals > 0 for r in blocked):10}  '
             f'{len(reachable):9}  {len(planned):7} ({share:5.1f} %)  {hits:4} / {peer_hits:<4}  '
             f'{missed:12}')
    both = [r for r in planned if r.ompl_motion is not None]
    ratios = [r.detour_motion / r.ompl_motion for r in both]
    faster = sum(q <= 1.0 + 1e-9 for q in ratios)
    best = [min(r.detour_motion, r.ompl_motion) for r in both]
    second = (f'{len(both):4}  {faster:4} ({100 * faster / max(len(both), 1):5.1f} %)  '
              f'{_median(ratios):12.3f}  '
              f'{_median([r.detour_motion / b for r, b in zip(both, best)]):6.3f} / '
              f'{_median([r.ompl_motion / b for r, b in zip(both, best)]):<6.3f}  '
              f'{1e3 * _median([r.time_with_detours for r in planned]):8.0f}  '
              f'{1e3 * _median([r.ompl_time for r in both]):8.0f}  '
              f'{_median([r.time_with_detours / r.direct_time for r in planned]):10.2f}')
    free = [r for r in mine if r.same_with_detours is not None]
    third = (f'{len(free):5}  {sum(r.same_with_detours for r in free):9}  '
             f'{1e3 * _median([r.direct_time for r in free]):9.1f}  '
             f'{1e3 * _median([r.time_with_detours for r in free]):9.1f}  '
             f'{_median([r.time_with_detours / r.direct_time for r in free]):6.3f}')
    return first, second, third


def _report(rows: list[Row]) -> str:
    """Return the three tables per arm."""
    tables = (['arm      goals  blocked  clear pose  reachable  planned (of reachable)  '
               'collisions (ours / OMPL)  direct after all'],
              ['arm      both  no slower than OMPL  median ratio  to best (ours / OMPL)  '
               'ours ms  OMPL ms  ours/direct'],
              ['arm      free direct  same  ms detours off  ms on  on/off'])
    for name in dict.fromkeys(r.arm for r in rows):
        mine = [r for r in rows if r.arm == name]
        for table, line in zip(tables, _arm_lines(mine)):
            table.append(f'{name:8} {line}')
        tables[0].extend(f'    collision {r.scene}/{r.seed}: {", ".join(r.detour_broken)}'
                         for r in mine if r.detour_broken)
    return '\n\n'.join('\n'.join(t) for t in tables)


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``trajplan bench-detours``."""
    p = sub.add_parser('bench-detours', help='measure motions around obstacles against OMPL',
                       description=__doc__.split('\n\n')[0].strip())
    add_scene_arguments(p, 20, "joint solutions drawn per blocked goal: OMPL's joint goals")
    p.add_argument('--ompl-time', type=float, default=10.0, metavar='S',
                   help="RRTConnect's budget per goal (the judge of reachable)")
    p.add_argument('--ompl-simplify', type=float, default=1.0, metavar='S',
                   help="the budget of OMPL's path simplification")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Run the bench and print its tables."""
    seed = bench_seed(args)
    print(f'bench-detours --arms {" ".join(args.arms)} --seed {seed} --scenes {args.scenes} '
          f'--goals {args.goals} --brute {args.brute} --ompl-time {args.ompl_time} '
          f'--ompl-simplify {args.ompl_simplify} --angular-velocity {args.angular_velocity} '
          f'--padding {args.padding} --obstacles {args.obstacles}', flush=True)
    prepare()
    ompl_peer.seed(seed)
    rows = measure_scenes(args, np.random.default_rng(seed), _measure,
                          lambda mine: f'blocked so far {sum(r.blocked for r in mine)}')
    print(_report(rows))
    return 0
