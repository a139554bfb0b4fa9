# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Command-line argument types and the usage error shared by the ``trajplan`` subcommands."""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from trajplan_ros.collision.distances import ArmCollision, CollisionWorld, DEFAULT_PADDING
from trajplan_ros.collision.scene import Scene
from trajplan_ros.collision.shapes import MeshSource
from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.motion.motion_profile import MotionProfile, Profile, Timing
from trajplan_ros.search.goal import (DEFAULT_AXIS_TOLERANCE, DEFAULT_ORIENTATION_TOLERANCE,
                                      DEFAULT_TOLERANCE)
from trajplan_ros.search.objective import DEFAULT_OMEGA

__all__ = ['TOLERANCES', 'UsageError', 'add_arm_arguments', 'add_collision_arguments',
           'add_motion_arguments', 'add_tolerance_arguments', 'arm_from_arguments',
           'finite_number', 'motion_from_arguments', 'package_share', 'positive_count',
           'tolerances_from_arguments', 'world_from_arguments']

#: The goal's tolerances by ``Goal``'s names (the flags: --tolerance, ...).
TOLERANCES = ('tolerance', 'axis_tolerance', 'orientation_tolerance')


class UsageError(Exception):
    """Bad command-line input; the message is the one-line reason."""


def finite_number(text: str) -> float:
    """Parse a finite float, for argparse."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a number: {text!r}') from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f'not a finite number: {text!r}')
    return value


def positive_count(text: str) -> int:
    """Parse an integer of at least 1, for argparse."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not an integer: {text!r}') from None
    if value < 1:
        raise argparse.ArgumentTypeError(f'must be at least 1, got {value}')
    return value


def add_arm_arguments(parser: argparse.ArgumentParser) -> None:
    """Add --urdf, --base-link, --tip-link, --tool-offset and --tool-axis (default: paper arm)."""
    group = parser.add_argument_group('arm (default: the paper arm, DH)')
    group.add_argument('--urdf', metavar='FILE',
                       help='plan for the chain of this URDF: every revolute joint from the base '
                            'link to the tip link (joint names and limits from the file)')
    group.add_argument('--base-link', metavar='NAME', help='chain start (default: the URDF root)')
    group.add_argument('--tip-link', metavar='NAME',
                       help='chain end (default: where the only chain of revolute joints ends)')
    group.add_argument('--tool-offset', nargs=3, type=finite_number, metavar=('X', 'Y', 'Z'),
                       default=(0.0, 0.0, 0.0), help='tool point in the tip frame, m')
    group.add_argument('--tool-axis', nargs=3, type=finite_number, metavar=('X', 'Y', 'Z'),
                       default=(0.0, 0.0, 1.0),
                       help='tool axis in the tip frame (radial and approach modes)')


def arm_from_arguments(args: argparse.Namespace) -> ArmModel:
    """Return the arm the arguments name (InvalidArmModel, a ValueError, with the reason)."""
    if args.urdf is None:
        given = [flag for flag, value in (('--base-link', args.base_link),
                                          ('--tip-link', args.tip_link)) if value is not None]
        if given or tuple(args.tool_offset) != (0.0, 0.0, 0.0) or tuple(args.tool_axis) != (
                0.0, 0.0, 1.0):
            raise UsageError(f"{', '.join(given) or '--tool-offset/--tool-axis'} needs --urdf")
        return paper_arm()
    return ArmModel.from_urdf(args.urdf, args.base_link, args.tip_link,
                              tool_offset=args.tool_offset, tool_axis=args.tool_axis)


def add_motion_arguments(parser: argparse.ArgumentParser) -> None:
    """Add --profile, --timing, --joint-limits, --max-acceleration, --max-jerk, the scalings."""
    group = parser.add_argument_group("motion (default: the paper's servo law, eq. 10)")
    group.add_argument('--profile', choices=[p.value for p in Profile], default='servo',
                       help="each joint's velocity profile: servo (starts and stops at once), "
                            'trapezoidal (acceleration-limited) or jerk_limited; the planner '
                            'minimises its duration (default %(default)s)')
    group.add_argument('--timing', choices=[t.value for t in Timing], default='independent',
                       help='independent: each joint stops at its own time; synchronized: all '
                            'arrive together (default %(default)s)')
    group.add_argument('--joint-limits', metavar='FILE',
                       help="MoveIt's joint_limits.yaml: per-joint max_velocity, "
                            'max_acceleration, max_jerk')
    group.add_argument('--max-acceleration', type=finite_number, metavar='RAD_S2',
                       help='acceleration limit of every joint the file gives none, rad/s^2')
    group.add_argument('--max-jerk', type=finite_number, metavar='RAD_S3',
                       help='jerk limit of every joint the file gives none, rad/s^3')
    group.add_argument('--velocity-scaling', type=finite_number, metavar='S',
                       help='scale every velocity limit by S in (0, 1], as MoveIt does '
                            "(default: the file's default_velocity_scaling_factor, else 1)")
    group.add_argument('--acceleration-scaling', type=finite_number, metavar='S',
                       help='scale every acceleration limit by S in (0, 1] (default: the '
                            "file's default_acceleration_scaling_factor, else 1)")


def motion_from_arguments(args: argparse.Namespace) -> MotionProfile:
    """Return the motion the arguments set (ValueError with the reason)."""
    return MotionProfile.from_file(args.joint_limits, profile=args.profile, timing=args.timing,
                                   max_acceleration=args.max_acceleration,
                                   max_jerk=args.max_jerk,
                                   velocity_scaling=args.velocity_scaling,
                                   acceleration_scaling=args.acceleration_scaling)


def add_tolerance_arguments(parser: argparse.ArgumentParser, several: bool = False) -> None:
    """
    Add the goal's tolerances: the region the plan reaches fastest (``Goal``).

    ``several``: each flag takes one or more values (a benchmark of each).
    """
    group = parser.add_argument_group(
        "the goal's tolerances (the plan is the fastest motion into the region they make)")
    many = {'nargs': '+'} if several else {}
    group.add_argument('--tolerance', type=finite_number, metavar='M', **many,
                       help='largest distance of the tool point from the goal '
                            f'(default {DEFAULT_TOLERANCE:g})')
    group.add_argument('--axis-tolerance', type=finite_number, metavar='RAD', **many,
                       help='largest angle between the tool axis and the goal ray (radial) or '
                            'the approach direction (default '
                            + ', '.join(f'{k} {v:g}' for k, v in DEFAULT_AXIS_TOLERANCE.items())
                            + ')')
    group.add_argument('--orientation-tolerance', type=finite_number, metavar='RAD', **many,
                       help='largest angle of the rotation between the goal orientation and '
                            f"the tool's (default {DEFAULT_ORIENTATION_TOLERANCE:g})")


def tolerances_from_arguments(args: argparse.Namespace) -> dict[str, float]:
    """Return the tolerances given on the command line, by ``Goal``'s names."""
    return {name: getattr(args, name) for name in TOLERANCES if getattr(args, name) is not None}


def add_collision_arguments(parser: argparse.ArgumentParser) -> None:
    """Add --scene, --srdf and --padding (any of them turns the collision check on), --detours."""
    group = parser.add_argument_group('collisions (default: not checked)')
    group.add_argument('--scene', metavar='FILE',
                       help='YAML file of obstacles in the base frame (boxes, spheres, '
                            'cylinders); the plan keeps --padding from them and between links')
    group.add_argument('--srdf', metavar='FILE',
                       help="the arm's SRDF: its disable_collisions pairs are not checked "
                            '(default: computed as MoveIt Setup Assistant does)')
    group.add_argument('--padding', type=finite_number, metavar='M',
                       help=f'least clearance in metres (default {DEFAULT_PADDING})')
    group.add_argument('--detours', action=argparse.BooleanOptionalAction, default=True,
                       help='where no direct motion is free, plan the fastest free motion '
                            'found through up to four via points (default on)')


def package_share(package: str) -> str:
    """Return a ROS package's share folder through the ament index (AMENT_PREFIX_PATH)."""
    from ament_index_python.packages import get_package_share_directory
    return get_package_share_directory(package)


def world_from_arguments(args: argparse.Namespace, arm: ArmModel) -> CollisionWorld | None:
    """Return the collision world the arguments ask for, or None (InvalidCollisionInput)."""
    if args.scene is None and args.srdf is None and args.padding is None:
        return None
    srdf = None
    if args.srdf is not None:
        try:
            srdf = Path(args.srdf).read_text(encoding='utf-8')
        except (OSError, UnicodeDecodeError) as exc:
            raise UsageError(f'cannot read {args.srdf}: {getattr(exc, "strerror", exc)}'
                             ) from None
    urdf = args.urdf if args.urdf is not None else urdf_xml(arm, velocity=DEFAULT_OMEGA)
    folder = None if args.urdf is None else Path(args.urdf).resolve().parent
    model = ArmCollision.from_urdf(urdf, arm, meshes=MeshSource(package_share, folder),
                                   srdf=srdf)
    scene = Scene.from_file(args.scene) if args.scene is not None else Scene()
    padding = DEFAULT_PADDING if args.padding is None else args.padding
    return CollisionWorld(model, scene, padding)
