# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The ``trajplan bench-collisions`` subcommand: the collision targets, measured.

For each arm (the SO-101, UR5, xArm7 and Panda of example-robot-data, and the paper's arm) it
draws scenes with a fresh seed: a table under the base and 1 to ``--obstacles`` boxes, spheres
and cylinders around the arm, none within the padding of the arm at its start, and goals (the
tool point of random joint angles, outside every obstacle). Each goal is planned three ways:
without any check, with the arm's own links only, and with the scene. Then:

* never a collision: every plan that succeeds is sampled every millisecond and checked by
  python-fcl on the real shapes (``clearance.IndependentCheck``), which must find every pair
  farther apart than the padding;
* not needlessly refused: a brute-force search, ``--brute`` joint solutions of the goal (random
  joint vectors projected onto it and polished), each motion checked exactly in order of its
  motion time, gives the fastest free motion it finds; the planner must plan 99 % of the goals
  where it finds one, within 1 % of its motion time, and end none of them ``not_reached``;
* speed: the plan time's median, 90th and 99th percentile with the scene and without any check,
  the median with the arm's own links alone, and the ratios of the medians.

``--rows FILE`` also writes every goal's measurements, one JSON object a line.
"""
from __future__ import annotations

import argparse
from dataclasses import asdict, dataclass
import json
from pathlib import Path
import sys
import tempfile
import time
from typing import Any, Callable

import numpy as np
from trajplan_ros.collision.distances import ArmCollision, CollisionWorld, DEFAULT_PADDING
from trajplan_ros.collision.free_motion import check_motion, START_TOLERANCE, StartLimits
from trajplan_ros.collision.scene import Obstacle, Scene
from trajplan_ros.collision.shapes import MeshSource, Shape
from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.kinematics.rotations import rotation_matrix
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.motion.motion_profile import MotionProfile, Timing
from trajplan_ros.motion.trajectory import Trajectory
from trajplan_ros.planning.planner import plan, PlanRequest, PlanStatus, prepare
from trajplan_ros.search.free_goal import project_onto_goal
from trajplan_ros.search.goal import Goal
from trajplan_ros.search.objective import Objective
from trajplan_ros.search.polish import polish
from trajplan_ros.tools.arguments import positive_count
from trajplan_ros.tools.bench.cases import PUBLISHED, robots_dir
from trajplan_ros.tools.bench.clearance import IndependentCheck

__all__ = ['add_parser', 'add_scene_arguments', 'BenchArm', 'bench_seed', 'draw_goal',
           'draw_scene', 'every_millisecond', 'goal_solutions', 'measure_scenes']

#: Where each arm starts (free of itself), and its SRDF below robots_dir() if it has one.
STARTS = {'so101': ((0.0, 0.0, 0.0, 0.0, 0.0), None),
          'ur5': ((0.0, -1.57, 1.57, -1.57, -1.57, 0.0), 'ur_description/srdf/ur5.srdf'),
          'panda': ((0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785),
                    'panda_description/srdf/panda.srdf'),
          'xarm7': ((0.0,) * 7, 'xarm_description/srdf/xarm7.srdf'),
          'paper': ((0.0,) * 5, None)}


@dataclass
class BenchArm:
    """An arm of the bench: its model, URDF file, collision model and start."""

    name: str
    arm: ArmModel
    urdf: Path
    model: ArmCollision
    start: np.ndarray

    @classmethod
    def load(cls, name: str, folder: Path) -> BenchArm:
        """Return the arm ``name`` (paper: written as a URDF into ``folder``)."""
        start, srdf = STARTS[name]
        if name == 'paper':
            arm = paper_arm()
            urdf = folder / 'paper_arm.urdf'
            urdf.write_text(urdf_xml(arm, velocity=0.2))
        else:
            spec = PUBLISHED[name]
            arm, urdf = ArmModel.from_urdf(spec.urdf, spec.base_link, spec.tip_link), spec.urdf
        share = str(robots_dir().parent)
        model = ArmCollision.from_urdf(
            urdf, arm, meshes=MeshSource(lambda package: share),
            srdf=None if srdf is None else (robots_dir() / srdf).read_text())
        return cls(name, arm, urdf, model, np.array(start, dtype=float))


def _obstacle(rng: np.random.Generator, index: int, reach: float) -> Obstacle:
    """Return a random box, sphere or cylinder within the arm's reach."""
    kind = ('box', 'sphere', 'cylinder')[rng.integers(3)]
    size = reach * rng.uniform(0.05, 0.3)
    dims = {'box': (size, rng.uniform(0.3, 1.0) * size, rng.uniform(0.1, 1.0) * size),
            'sphere': (size / 3,), 'cylinder': (size, size / 6)}[kind]
    position = np.array([*rng.uniform(-reach, reach, 2), rng.uniform(0.0, reach)])
    axis = rng.normal(size=4)
    pose = np.eye(4)
    pose[:3, :3] = rotation_matrix(axis / np.linalg.norm(axis))
    pose[:3, 3] = position
    return Obstacle(f'{kind}{index}', Shape.primitive(kind, dims, pose, 'bench'))


def draw_scene(bench: BenchArm, rng: np.random.Generator, padding: float, most: int = 10
               ) -> CollisionWorld:
    """Return a table under the base and 1 to ``most`` obstacles clear of the arm's start."""
    reach = bench.arm.reach
    base = [link for link in bench.model.geometry.links if link.joint < 0]
    heights = (link.vertices() @ link.attachment[2, :3] + link.attachment[2, 3] for link in base)
    bottom = min((float(np.min(h)) for h in heights), default=0.0)
    table = np.eye(4)
    table[2, 3] = min(bottom, 0.0) - 0.001 - 0.02            # its top just under the base
    obstacles = [Obstacle('table', Shape.primitive('box', (2 * reach, 2 * reach, 0.04), table,
                                                   'bench'))]
    wanted = int(rng.integers(1, most + 1))
    poses = bench.model.geometry.link_poses(bench.start[None])[0]
    while len(obstacles) < wanted + 1:
        candidate = _obstacle(rng, len(obstacles), reach)
        world = CollisionWorld(bench.model, Scene((candidate,)), padding)
        pairs = np.flatnonzero(world.pairs[:, 1] >= len(bench.model.link_names))
        if not any(world.within(poses, p, 2 * padding) for p in pairs):
            obstacles.append(candidate)
    return CollisionWorld(bench.model, Scene(tuple(obstacles)), padding)


def draw_goal(bench: BenchArm, world: CollisionWorld, rng: np.random.Generator) -> np.ndarray:
    """Return the tool point of random joint angles, outside every obstacle."""
    lower = np.where(np.isfinite(bench.arm.lower), bench.arm.lower, -np.pi)
    upper = np.where(np.isfinite(bench.arm.upper), bench.arm.upper, np.pi)
    while True:
        goal = bench.arm.tool(rng.uniform(lower, upper)[None])[0][0]
        if world.obstacle_at(goal) is None and goal[2] > 0.0:
            return goal


def goal_solutions(bench: BenchArm, goal: np.ndarray, omega: float, count: int
                   ) -> tuple[Objective, np.ndarray]:
    """Return the goal's objective and ``count`` joint solutions' reached ones, fastest first."""
    obj = Objective(bench.arm, Goal(goal), bench.start, omega=omega)
    rng = np.random.default_rng(12345)
    projected = project_onto_goal(obj, rng.uniform(obj.lower, obj.upper, (count, obj.arm.planned)))
    x = np.vstack((projected, polish(obj, projected)))
    x = x[obj.errors(obj.tool(x)) <= 1e-6]
    return obj, x[np.argsort(obj.motion_time(x), kind='stable')]


def _brute_force(bench: BenchArm, world: CollisionWorld, goal: np.ndarray, omega: float,
                 count: int) -> float | None:
    """Return the fastest free motion time among ``count`` joint solutions, or None."""
    obj, x = goal_solutions(bench, goal, omega, count)
    law = MotionProfile().time_law(bench.arm, omega)
    limits = StartLimits.at(world, bench.start)
    for candidate in x:
        if check_motion(world, bench.start, obj.full(candidate)[0], law, Timing.INDEPENDENT,
                        limits=limits).free:
            return float(obj.motion_time(candidate[None])[0])
    return None


@dataclass
class Row:
    """One goal's measurements."""

    arm: str
    scene: int
    seed: int
    goal: list[float]
    obstacles: int
    status: str
    motion_time: float
    brute: float | None
    time_scene: float
    time_self: float
    time_none: float
    broken: list[str]           # python-fcl's pairs that break the padding along the plan


def every_millisecond(trajectory: Trajectory) -> np.ndarray:
    """Return a trajectory's joint angles every millisecond, the end included."""
    t = np.append(np.arange(0.0, trajectory.duration, 1e-3), trajectory.duration)
    return trajectory.at_time(t)[0]


def _measure(bench: BenchArm, world: CollisionWorld, check: IndependentCheck, goal: np.ndarray,
             args: argparse.Namespace, seed: int, scene: int) -> Row:
    """Plan one goal three ways, check the plan independently, and search by brute force."""
    omega = args.angular_velocity
    request = PlanRequest(goal, bench.start, arm=bench.arm, seed=seed, angular_velocity=omega)
    none = plan(request)
    own = plan(request.replace(world=CollisionWorld(bench.model, Scene(), world.padding)))
    result = plan(request.replace(world=world))
    broken = []
    if result.success:
        broken = check.violations(every_millisecond(result.trajectory(sample_period=1.0)),
                                  START_TOLERANCE)
    brute = _brute_force(bench, world, goal, omega, args.brute) if none.success else None
    return Row(bench.name, scene, seed, goal.tolist(), len(world.scene.obstacles) - 1,
               result.status.value,
               result.motion_time_s, brute, result.plan_time_s, own.plan_time_s,
               none.plan_time_s, broken)


def _percentiles(values: list[float]) -> str:
    """Return the median, 90th and 99th percentile of times (s) in ms, as 'a / b / c'."""
    return ' / '.join(f'{1e3 * v:.1f}' for v in np.percentile(values, (50, 90, 99)))


def _report(rows: list[Row]) -> str:
    """Return the tables of the targets per arm: answers, then plan times."""
    answers = ['arm      goals  planned  collisions  brute-free  planned of those  within 1 %  '
               'not_reached while free']
    times = ['arm      plan ms none: median / p90 / p99   self: median   '
             'scene: median / p90 / p99   self/none  scene/none']
    for name in dict.fromkeys(r.arm for r in rows):
        mine = [r for r in rows if r.arm == name]
        planned = [r for r in mine if r.status == PlanStatus.SUCCEEDED.value]
        hits = [r for r in planned if r.broken]
        free = [r for r in mine if r.brute is not None]
        kept = [r for r in free if r.status == PlanStatus.SUCCEEDED.value]
        close = [r for r in kept if r.motion_time <= 1.01 * r.brute + 1e-9]
        missed = [r for r in free if r.status == PlanStatus.NOT_REACHED.value]
        answers.append(f'{name:8} {len(mine):5}  {len(planned):7}  {len(hits):10}  '
                       f'{len(free):10}  {len(kept):16}  {len(close):10}  {len(missed):22}')
        answers += [f'    collision: {", ".join(r.broken)}' for r in hits]
        none, own, scene = ([getattr(r, k) for r in mine]
                            for k in ('time_none', 'time_self', 'time_scene'))
        times.append(f'{name:8} {_percentiles(none):>33}   {1e3 * np.median(own):12.1f}   '
                     f'{_percentiles(scene):>25}   {np.median(own) / np.median(none):9.2f}  '
                     f'{np.median(scene) / np.median(none):10.2f}')
    return '\n'.join(answers + [''] + times)


def add_scene_arguments(p: argparse.ArgumentParser, scenes: int, brute: str) -> None:
    """Add the flags of a bench over drawn scenes (``scenes``: its default; ``brute``: help)."""
    p.add_argument('--arms', nargs='+', default=['so101', 'ur5', 'panda', 'paper'],
                   choices=sorted(STARTS))
    p.add_argument('--scenes', type=positive_count, default=scenes, help='scenes per arm')
    p.add_argument('--goals', type=positive_count, default=5, help='goals per scene')
    p.add_argument('--brute', type=positive_count, default=400, help=brute)
    p.add_argument('--angular-velocity', '--omega', type=float, default=1.0, metavar='RAD_S',
                   help='servo angular velocity omega, rad/s')
    p.add_argument('--padding', type=float, default=DEFAULT_PADDING)
    p.add_argument('--obstacles', type=positive_count, default=10,
                   help='most obstacles per scene besides the table')
    p.add_argument('--rows', type=Path, default=None,
                   help="write every goal's measurements to this file (JSON lines)")
    p.add_argument('--seed', type=int, default=None, help='default: a fresh one, printed')


def bench_seed(args: argparse.Namespace) -> int:
    """Return ``--seed``, else a fresh one."""
    return args.seed if args.seed is not None else int(np.random.SeedSequence().entropy % 2**31)


def measure_scenes(args: argparse.Namespace, rng: np.random.Generator,
                   measure: Callable[..., Any],
                   note: Callable[[list[Any]], str] | None = None) -> list[Any]:
    """
    Return ``measure``'s row for every goal of every arm's scenes, drawn from ``rng``.

    ``measure(bench, world, check, goal, args, seed, scene)`` returns a dataclass; each row is
    appended to ``--rows`` as it comes. Progress goes to stderr, each scene's line ending with
    ``note(the arm's rows)`` if given.
    """
    rows: list[Any] = []
    with tempfile.TemporaryDirectory() as folder:
        for name in args.arms:
            clock = time.perf_counter()
            bench = BenchArm.load(name, Path(folder))
            print(f'{name}: collision model in {time.perf_counter() - clock:.1f} s '
                  f'({bench.model.skip_source})', file=sys.stderr, flush=True)
            for scene in range(args.scenes):
                world = draw_scene(bench, rng, args.padding, args.obstacles)
                check = IndependentCheck(world, bench.urdf)
                for _ in range(args.goals):
                    rows.append(measure(bench, world, check, draw_goal(bench, world, rng), args,
                                        int(rng.integers(2**31)), scene))
                    if args.rows is not None:
                        with args.rows.open('a', encoding='utf-8') as out:
                            out.write(json.dumps(asdict(rows[-1])) + '\n')
                extra = '' if note is None else f', {note([r for r in rows if r.arm == name])}'
                print(f'{name}: scene {scene + 1}/{args.scenes}{extra}', file=sys.stderr,
                      flush=True)
    return rows


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``trajplan bench-collisions``."""
    p = sub.add_parser('bench-collisions', help='measure the collision targets',
                       description=__doc__.split('\n\n')[0].strip())
    add_scene_arguments(p, 10, 'joint solutions of the brute-force search per goal')
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Run the bench and print its table."""
    seed = bench_seed(args)
    print(f'bench-collisions --arms {" ".join(args.arms)} --seed {seed} --scenes '
          f'{args.scenes} --goals {args.goals} --brute {args.brute} --angular-velocity '
          f'{args.angular_velocity} --padding {args.padding} --obstacles {args.obstacles}',
          flush=True)
    prepare()
    rows = measure_scenes(args, np.random.default_rng(seed), _measure)
    print(_report(rows))
    return 0
