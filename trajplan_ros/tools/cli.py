# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The ``trajplan`` command: plan goals from the shell, one at a time or from a CSV file."""
from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path
import sys
from typing import Any, NamedTuple, Sequence

import numpy as np
from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.planning.planner import (ALGORITHMS, describe_residual, plan, PlanRequest,
                                           PlanResult, PlanStatus, prepare)
from trajplan_ros.search.goal import Goal, Mode, TOP_DOWN
from trajplan_ros.search.objective import DEFAULT_OMEGA
from trajplan_ros.tools import bench, demo, figures, node_commands
from trajplan_ros.tools.arguments import (add_arm_arguments, add_collision_arguments,
                                          add_motion_arguments, add_tolerance_arguments,
                                          arm_from_arguments, finite_number,
                                          motion_from_arguments, positive_count,
                                          tolerances_from_arguments, UsageError,
                                          world_from_arguments)
from trajplan_ros.tools.bench import collision_bench, detour_bench


__all__ = ['main', 'build_parser']


def _add_plan(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser('plan', help='plan the joint goal and motion for tool positions',
                       description='Plan with the paper arm or a URDF chain (--urdf). Units: '
                                   'metres, radians.')
    p.add_argument('xyz', nargs='*', type=finite_number, metavar='X Y Z',
                   help='goal position of the tool in metres (omit with --goals)')
    p.add_argument('--goals', metavar='FILE',
                   help='CSV file, one goal a line: x,y,z[,ax,ay,az | ,qx,qy,qz,qw][,start '
                        'angles]; a header line names the columns (x,y,z, ax,ay,az for an '
                        'approach or qx,qy,qz,qw for a pose, then the joints by name, or any '
                        "names for chain order); '-' for stdin")
    p.add_argument('--start', nargs='+', type=finite_number, metavar='Q',
                   help='start joint angles in radians (default: upright, all zero)')
    p.add_argument('--joint-goal', nargs='+', type=finite_number, metavar='Q',
                   help='plan the motion to these joint angles (radians) instead of a tool '
                        'position: direct, or around the --scene through via points')
    p.add_argument('--mode', choices=[m.value for m in Mode],
                   help='free (position only), radial (eq. 12-13), approach (the tool axis '
                        'along --approach) or pose (the tool frame at --orientation); default '
                        'approach with --approach, pose with --orientation, else free')
    p.add_argument('--approach', nargs=3, type=finite_number, metavar=('AX', 'AY', 'AZ'),
                   help='approach direction of the tool axis in the base frame (default '
                        '0 0 -1: from above)')
    p.add_argument('--orientation', nargs=4, type=finite_number,
                   metavar=('QX', 'QY', 'QZ', 'QW'),
                   help="the tool frame's orientation in the base frame, a unit quaternion")
    p.add_argument('--algorithm', choices=list(ALGORITHMS), default='iepso')
    p.add_argument('--seed', type=int, default=0, help='random seed (default 0)')
    add_tolerance_arguments(p)
    p.add_argument('--start-limit-margin', type=finite_number, default=0.05, metavar='RAD',
                   help='a start joint this far outside its limits is planned from, the motion '
                        'bringing it inside (default %(default)s)')
    p.add_argument('--max-planning-time', type=finite_number, default=None, metavar='S',
                   help='longest search per goal in seconds; past it the plan ends as timed_out '
                        'with its best answer (default: no limit)')
    p.add_argument('--angular-velocity', type=finite_number, default=DEFAULT_OMEGA,
                   metavar='RAD_S', help='servo angular velocity omega in rad/s, capped per '
                   "joint by its URDF velocity limit (default %(default)s, the node's default)")
    p.add_argument('--json', action='store_true', help='print one JSON object a line')
    p.add_argument('--trajectory', action='store_true',
                   help='with --json: add the JointTrajectory the node would publish, as '
                        '"trajectory": {"joint_names", "points": [{"time_from_start", '
                        '"positions", "velocities", "accelerations"}]} (null unless planned)')
    p.add_argument('--sample-period', type=finite_number, default=0.1, metavar='S',
                   help='time between trajectory points in seconds (default %(default)s)')
    p.add_argument('--max-trajectory-points', type=positive_count, default=10000, metavar='N',
                   help='a longer trajectory is not built: "trajectory" is null and the '
                        "message says why (default %(default)s, the node's default)")
    add_arm_arguments(p)
    add_motion_arguments(p)
    add_collision_arguments(p)
    p.set_defaults(run=_run_plan)


def _add_urdf(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser('urdf', help='print the arm as a URDF (for robot_state_publisher and RViz)',
                       description='Print the default (paper) arm as a URDF whose joint values '
                                   "are the planner's joint angles q.")
    p.add_argument('-o', '--output', metavar='FILE', help='write to FILE instead of printing')
    p.add_argument('--name', default='paper_arm', help='robot name (default paper_arm)')
    p.set_defaults(run=_run_urdf)


def _run_urdf(args: argparse.Namespace) -> int:
    text = urdf_xml(paper_arm(), args.name, velocity=DEFAULT_OMEGA)
    if args.output is None:
        sys.stdout.write(text)
    else:
        Path(args.output).write_text(text, encoding='utf-8')
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog='trajplan', description='Direct trajectory planning with IEPSO (Lv et al. 2019).')
    sub = parser.add_subparsers(dest='command', required=True)
    _add_plan(sub)
    # each subcommand imports its optional extras (scipy, matplotlib, rclpy) only when it runs
    for add_parser in (node_commands.add_call_parser, node_commands.add_goal_parser,
                       bench.add_parser, collision_bench.add_parser, detour_bench.add_parser,
                       figures.add_parser, _add_urdf, demo.add_parser):
        add_parser(sub)
    return parser


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


class Layout(NamedTuple):
    """The columns of a goals CSV: after x, y, z an approach, an orientation or neither."""

    #: The columns after x, y, z that say how the tool points: (), ax,ay,az or qx,qy,qz,qw.
    pointing: tuple[str, ...] = ()
    #: The start columns' joint names in file order; None: the chain's order.
    joints: tuple[str, ...] | None = None


#: The columns a goals CSV may give after x, y, z, and the mode each asks for.
POINTING = {('ax', 'ay', 'az'): Mode.APPROACH, ('qx', 'qy', 'qz', 'qw'): Mode.POSE}


def _layout(header: list[str], arm: ArmModel) -> Layout:
    """Return the layout a header line names (UsageError for one that cannot be planned)."""
    names = [c.lower() for c in header]
    if names[:3] != ['x', 'y', 'z']:
        raise UsageError(f"a header must start with x,y,z, got {','.join(header[:3])}")
    pointing = next((p for p in POINTING if tuple(names[3:3 + len(p)]) == p), ())
    rest = tuple(header[3 + len(pointing):])
    if not rest or not set(rest) <= set(arm.joint_names):
        return Layout(pointing)
    if sorted(rest) != sorted(arm.joint_names[:len(rest)]) or len(set(rest)) != len(rest):
        raise UsageError(f"the header's joints {', '.join(rest)} are not the arm's first "
                         f"{len(rest)} joints ({', '.join(arm.joint_names)})")
    return Layout(pointing, rest)


def _goal_lines(path: str, arm: ArmModel) -> tuple[Layout, list[tuple[int, list[str]]]]:
    """Return the CSV's layout and its data lines (number, fields): no blanks or comments."""
    handle = sys.stdin if path == '-' else open(path, newline='', encoding='utf-8')
    layout, lines, first = Layout(), [], True
    with handle:
        for number, row in enumerate(csv.reader(handle), start=1):
            cells = [c.strip() for c in row]
            if len(cells) <= 1 and not any(cells) or cells and cells[0].startswith('#'):
                continue                                  # a blank line or a comment
            if first and not any(_is_number(c) for c in cells):     # e.g. x,y,z,ax,ay,az,...
                layout = _layout(cells, arm)
            else:
                lines.append((number, cells))
            first = False
    return layout, lines


def _parse_line(cells: list[str], layout: Layout, arm: ArmModel
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Return a line's goal, its approach or orientation (or nothing) and start (or None)."""
    head = 3 + len(layout.pointing)
    expected = ','.join(('x', 'y', 'z') + layout.pointing) + '[,start angles]'
    if len(cells) < head:
        raise UsageError(f'expected {expected}, got {len(cells)} field(s)')
    if not all(cells):
        empty = [str(i + 1) for i, c in enumerate(cells) if not c]
        raise UsageError(f"empty field(s) {', '.join(empty)}: expected {expected}")
    try:
        values = np.array([float(c) for c in cells])
    except ValueError as exc:
        raise UsageError(f'not a number: {exc}') from None
    start = values[head:] if len(values) > head else None
    if start is not None and layout.joints is not None:
        if len(start) != len(layout.joints):
            raise UsageError(f'expected {len(layout.joints)} start angles '
                             f"({', '.join(layout.joints)}), got {len(start)}")
        start = start[[layout.joints.index(j) for j in arm.joint_names[:len(start)]]]
    return values[:3], values[3:head], start


def _human(result: PlanResult, arm: ArmModel) -> str:
    goal = ', '.join(f'{v:.6g}' for v in result.goal)
    lines = [f'goal ({goal}) m: {result.status.value}: {result.message}']
    if result.joint_goal is not None:
        lines.append('joint goal [rad]: ' + '  '.join(
            f'{name}={v:+.6f}' for name, v in zip(arm.joint_names, result.joint_goal)))
        motion = result.motion
        law = '' if motion == MotionProfile() else f' ({motion.describe()})'
        turn = ('' if np.isnan(result.orientation_error_rad) else
                f", orientation error {describe_residual(result.orientation_error_rad, 'rad')}")
        score = ('' if np.isnan(result.efficiency) else     # F is a direct motion's (eq. 9)
                 f', efficiency F {result.efficiency:.4f}')
        lines.append(f'motion time {result.motion_time_s:.4f} s{law}, position error '
                     f"{describe_residual(result.position_error_m, 'm')}{turn}{score}, "
                     f'{result.iterations} iterations, '
                     f'planned in {1e3 * result.plan_time_s:.1f} ms')
    return '\n'.join(lines)


def _record(result: PlanResult, line: int | None, arm: ArmModel,
            args: argparse.Namespace) -> dict[str, Any]:
    """
    Return the JSON line of a plan: the same keys every time (null where no value).

    ``joint_names`` names the entries of ``joint_goal``: the chain's joints from the base.
    With ``--trajectory``, ``trajectory`` is the message a planned goal gives (else null).
    """
    record = {'line': line, **result.to_dict(), 'joint_names': list(arm.joint_names)}
    if args.trajectory:
        record['trajectory'] = None
        if result.success:
            period = args.sample_period
            points = result.trajectory_points(sample_period=period)
            if points <= args.max_trajectory_points:
                record['trajectory'] = result.trajectory(sample_period=period).to_dict()
            else:
                record['message'] += (f'; no trajectory: it would need {points} points, more '
                                      f'than --max-trajectory-points {args.max_trajectory_points}')
    return record


def _line(result: PlanResult, line: int | None, arm: ArmModel,
          args: argparse.Namespace) -> str:
    """Return what ``trajplan plan`` prints for one plan: a JSON line or the human lines."""
    return json.dumps(_record(result, line, arm, args)) if args.json else _human(result, arm)


def _unparsed(line: int, reason: str, args: argparse.Namespace, arm: ArmModel
              ) -> dict[str, Any]:
    """Return the JSON line of a CSV line without a goal: a rejected plan, goal null."""
    request = args.request
    rejected = PlanResult(PlanStatus.REJECTED, f'line {line}: {reason}', goal=np.full(3, np.nan),
                          start=None, algorithm=request.algorithm, mode=request.goal.mode.value,
                          angular_velocity=request.angular_velocity, motion=request.motion)
    return {**_record(rejected, line, arm, args), 'goal': None}


def _goal(args: argparse.Namespace) -> Goal:
    """Return the goal of ``trajplan plan``'s flags: its kind and tolerances, no point yet."""
    implied = (Mode.APPROACH.value if args.approach else
               Mode.POSE.value if args.orientation else Mode.FREE.value)
    mode = args.mode or implied
    for flag, needs in (('approach', Mode.APPROACH.value), ('orientation', Mode.POSE.value)):
        if getattr(args, flag) and mode != needs:
            raise UsageError(f'--{flag} needs --mode {needs}, not {mode}')
    return Goal(mode=mode, approach=args.approach or TOP_DOWN, orientation=args.orientation,
                **tolerances_from_arguments(args))


def _request(args: argparse.Namespace, arm: ArmModel) -> PlanRequest:
    """Return the settings of ``trajplan plan``'s flags as a request (its goal's point empty)."""
    request = PlanRequest(
        _goal(args), arm=arm, motion=motion_from_arguments(args),
        angular_velocity=args.angular_velocity, world=world_from_arguments(args, arm),
        algorithm=args.algorithm, seed=args.seed,
        max_planning_time=args.max_planning_time, start_limit_margin=args.start_limit_margin,
        detours=args.detours)
    request.validate()
    return request


def _run_plan(args: argparse.Namespace) -> int:
    arm = arm_from_arguments(args)
    if args.trajectory and not args.json:
        raise UsageError('--trajectory needs --json')
    if not args.sample_period > 0:
        raise UsageError('--sample-period must be positive')
    args.request = request = _request(args, arm)
    ignored = request.motion.ignored_joints(arm)
    if ignored:
        print(f"trajplan: warning: the joint limits' joints {', '.join(ignored)} are not "
              'planned: ignored', file=sys.stderr)
    kernels = prepare(request, announce=lambda text: print(f'trajplan: {text}', file=sys.stderr,
                                                           flush=True))
    if kernels.compiled:                                   # the first run after an install
        print(f'trajplan: {kernels.describe()}', file=sys.stderr)
    if args.joint_goal is not None:
        if args.xyz or args.goals is not None:
            raise UsageError('give X Y Z, --goals FILE or --joint-goal Q..., one of them')
        start = None if args.start is None else arm.full_start(args.start)   # ValueError: exit 2
        result = plan(request.replace(goal=request.goal.replace(joint_goal=args.joint_goal),
                                      start=start))
        print(_line(result, None, arm, args))
        return 0 if result.success else 1
    if args.goals is None:
        if len(args.xyz) != 3:
            raise UsageError('give a goal as X Y Z (3 numbers) or --goals FILE, '
                             f'got {len(args.xyz)} number(s)')
        start = None if args.start is None else arm.full_start(args.start)   # ValueError: exit 2
        result = plan(request.replace(goal=request.goal.replace(position=args.xyz), start=start))
        print(_line(result, None, arm, args))
        return 0 if result.success else 1
    if args.xyz:
        raise UsageError('give either X Y Z or --goals FILE, not both')
    try:
        layout, lines = _goal_lines(args.goals, arm)
    except OSError as exc:
        raise UsageError(f'cannot read {args.goals}: {exc.strerror}') from None
    failures = 0
    for number, cells in lines:
        try:
            position, pointing, start = _parse_line(cells, layout, arm)
            goal = request.goal.replace(position=position)
            if layout.pointing:
                mode = POINTING[layout.pointing]
                goal = goal.replace(mode=mode, **({'approach': pointing, 'orientation': None}
                                                  if mode is Mode.APPROACH
                                                  else {'orientation': pointing}))
            line_request = request.replace(goal=goal, start=args.start if start is None
                                           else start)
            line_request.validate()
        except (UsageError, ValueError) as exc:
            failures += 1
            record = _unparsed(number, str(exc), args, arm)
            print(json.dumps(record) if args.json else record['message'])
            continue
        result = plan(line_request)
        failures += not result.success
        print(_line(result, number, arm, args))
    return 0 if failures == 0 else 1


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.run(args)
    except (UsageError, ValueError) as exc:
        print(f'trajplan: error: {exc}', file=sys.stderr)
        return 2
    except TimeoutError as exc:
        print(f'trajplan: {exc}', file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130


if __name__ == '__main__':
    sys.exit(main())
