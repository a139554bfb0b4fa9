# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The planner node's parameters: one table of names, defaults and ranges, and their checking.

``PARAMETERS`` is the single source of the node's parameters: the node declares each with a
descriptor built from it, and ``config/params.yaml`` repeats its defaults (a test holds the two
equal). ``Settings.from_parameters`` turns a full set of values into the settings of the next
plan, or refuses them with a one-line reason. Nothing here imports rclpy.

The arm comes from a URDF when there is one: the ``robot_description`` parameter when it is set,
else the last description received on the ``robot_description`` topic. Then the chain from
``base_link`` to ``tip_link`` is planned (every revolute joint on it, with the URDF's names and
limits), the ``arm.*`` DH parameters are ignored, ``start_positions`` must list every chain
joint (its untouched default, five zeros for the paper arm, means all zeros; a description
that arrives while it lists other joints is not refused for it: the start is then all zeros
until ``start_positions`` is set to match) and ``base_frame``,
left at its default, becomes the chain's base link. Without a description the ``arm.*``
parameters (the paper arm) apply.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import functools
from typing import Any, Mapping

from ament_index_python.packages import get_package_share_directory
import numpy as np
from trajplan_ros.collision.distances import ArmCollision, CollisionWorld, DEFAULT_PADDING
from trajplan_ros.collision.scene import Scene
from trajplan_ros.collision.shapes import MeshSource
from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.kinematics.frames import RobotFrames
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.motion.motion_profile import MotionProfile, Profile, Timing
from trajplan_ros.planning import (ALGORITHMS, DEFAULT_AXIS_TOLERANCE,
                                   DEFAULT_ORIENTATION_TOLERANCE, DEFAULT_TOLERANCE, Mode,
                                   PlanRequest)
from trajplan_ros.search.goal import Goal, TOP_DOWN
from trajplan_ros.search.objective import DEFAULT_OMEGA


__all__ = ['PARAMETERS', 'ParameterSpec', 'Settings', 'default_values']


@dataclass(frozen=True)
class ParameterSpec:
    """One node parameter: its default, what it means, and the range or choices it accepts."""

    name: str
    default: Any
    description: str
    #: inclusive (low, high) bounds; the type of the default says whether they are integers
    bounds: tuple[float, float] | None = None
    choices: tuple[str, ...] = ()


def _arm_specs() -> list[ParameterSpec]:
    arm = paper_arm()
    a, alpha, d = arm.dh
    values = {'a': a, 'alpha': alpha, 'd': d, 'offset': arm.offset, 'lower': arm.lower,
              'upper': arm.upper}
    vectors = {
        'a': 'DH link lengths a_i, m', 'alpha': 'DH link twists alpha_i, rad',
        'd': 'DH link offsets d_i, m',
        'offset': 'joint angle offsets, rad (theta_i = sign_i q_i + offset_i)',
        'lower': 'lower joint limits on q, rad', 'upper': 'upper joint limits on q, rad',
    }
    specs = [ParameterSpec(f'arm.{key}', values[key].tolist(), f'{meaning}, one per joint')
             for key, meaning in vectors.items()]
    return specs + [
        ParameterSpec('arm.sign', [int(s) for s in arm.sign],
                      'joint direction signs (+1 or -1) in theta_i = sign_i q_i + offset_i'),
        ParameterSpec('arm.joint_names', list(arm.joint_names),
                      'joint names, base to tool, as in joint_states and the published '
                      'trajectory'),
        ParameterSpec('arm.planned', arm.planned,
                      'how many leading joints are planned; the rest hold', bounds=(2, 7)),
        ParameterSpec('start_positions', [0.0] * arm.n_joints,
                      'start joint angles, rad, used until joint_states or a published '
                      'trajectory tells the state'),
    ]


#: The controller's action unless ``controller_action`` says otherwise (relative, as
#: joint_trajectory_controller serves it in its own namespace).
CONTROLLER_ACTION = 'follow_joint_trajectory'

#: Every parameter of the node, in declaration order.
PARAMETERS: tuple[ParameterSpec, ...] = (
    ParameterSpec('robot_description', '',
                  'URDF of the arm (XML text); empty: the robot_description topic, else the '
                  'arm.* DH parameters'),
    ParameterSpec('base_link', '', 'first link of the planned chain; empty: the URDF root'),
    ParameterSpec('tip_link', '',
                  'last link of the planned chain; empty: where the only chain of revolute '
                  'joints ends'),
    ParameterSpec('tool_offset', [0.0, 0.0, 0.0], 'tool point in the tip link frame, m'),
    ParameterSpec('tool_axis', [0.0, 0.0, 1.0],
                  'tool axis in the tip link frame (radial and approach modes use it)'),
    *_arm_specs(),
    ParameterSpec('angular_velocity', DEFAULT_OMEGA,
                  "servo angular velocity omega, rad/s; it caps every joint's velocity limit",
                  bounds=(1e-3, 10.0)),
    ParameterSpec('profile', Profile.SERVO.value,
                  "each joint's velocity profile: servo (eq. 10), trapezoidal (acceleration "
                  'limits) or jerk_limited; the planner minimises its duration',
                  choices=tuple(p.value for p in Profile)),
    ParameterSpec('timing', Timing.INDEPENDENT.value,
                  'independent: each joint stops at its own time; synchronized: all together',
                  choices=tuple(t.value for t in Timing)),
    ParameterSpec('joint_limits_file', '',
                  "MoveIt's joint_limits.yaml (per-joint max_velocity, max_acceleration, "
                  'max_jerk, default scaling factors; joints not planned, such as a gripper, '
                  'are ignored with a warning); empty: none'),
    ParameterSpec('velocity_scaling', 0.0,
                  'velocity limits times this, in (0, 1], as MoveIt scales them; 0: '
                  "joint_limits_file's default_velocity_scaling_factor, else 1",
                  bounds=(0.0, 1.0)),
    ParameterSpec('acceleration_scaling', 0.0,
                  "acceleration limits times this, in (0, 1]; 0: joint_limits_file's "
                  'default_acceleration_scaling_factor, else 1', bounds=(0.0, 1.0)),
    ParameterSpec('max_acceleration', 0.0,
                  'acceleration limit of every joint joint_limits_file gives none, rad/s^2; '
                  '0: none', bounds=(0.0, 1e6)),
    ParameterSpec('max_jerk', 0.0,
                  'jerk limit of every joint joint_limits_file gives none, rad/s^3; 0: none',
                  bounds=(0.0, 1e9)),
    ParameterSpec('collision_check', False,
                  'plan motions that keep padding from the scene and between the links (the '
                  "URDF's <collision> shapes); false: no check; default true with "
                  'moveit_interfaces'),
    ParameterSpec('robot_description_semantic', '',
                  'SRDF of the arm (XML text): its disable_collisions pairs are skipped; empty: '
                  'the robot_description_semantic topic, else computed as MoveIt Setup '
                  'Assistant does'),
    ParameterSpec('scene_file', '',
                  'YAML file of obstacles in the base frame (boxes, spheres, cylinders); '
                  'empty: none but those on collision_objects'),
    ParameterSpec('padding', DEFAULT_PADDING,
                  'least clearance a motion keeps from obstacles and between links, m',
                  bounds=(0.0, 1.0)),
    ParameterSpec('detours', True,
                  'with collision_check: where no direct motion is free, plan the fastest free '
                  'motion found through up to four via points'),
    ParameterSpec('mode', Mode.FREE.value,
                  'free: position only; radial: the tool axis along the goal ray too '
                  '(eq. 12-13); approach: along approach_direction (a full pose comes with '
                  'each goal: goal_orientation pose)',
                  choices=tuple(m.value for m in Mode if m is not Mode.POSE)),
    ParameterSpec('approach_direction', list(TOP_DOWN),
                  'approach mode: the direction of the tool axis in base_frame for Point goals '
                  '(0, 0, -1: from above)'),
    ParameterSpec('goal_orientation', 'ignore',
                  "how a pose goal's orientation is used (goal_pose, plan_trajectory, "
                  'compute_plan): ignore; approach (the tool axis along its z axis; Point '
                  'goals then take approach_direction); or pose (the tool frame takes the '
                  'whole orientation; Point goals plan in mode)',
                  choices=('ignore', 'approach', 'pose')),
    ParameterSpec('algorithm', 'iepso', 'optimiser', choices=tuple(ALGORITHMS)),
    ParameterSpec('population', 40, 'particles per swarm', bounds=(2, 10000)),
    ParameterSpec('max_iterations', 1000, 'iteration cap', bounds=(1, 1000000)),
    ParameterSpec('seed', 0, 'random seed; -1: a fresh seed every plan', bounds=(-1, 2**31 - 1)),
    ParameterSpec('tolerance', DEFAULT_TOLERANCE,
                  'largest position error that counts as reached, m '
                  '(a GetPlan tolerance > 0 wins)', bounds=(1e-12, 1.0)),
    ParameterSpec('axis_tolerance', 0.0,
                  'largest angle between the tool axis and the goal ray (radial) or the '
                  'approach direction that counts as met, rad; 0: '
                  + ', '.join(f'{v:g} in {k} mode' for k, v in DEFAULT_AXIS_TOLERANCE.items()),
                  bounds=(0.0, 3.2)),
    ParameterSpec('orientation_tolerance', DEFAULT_ORIENTATION_TOLERANCE,
                  'goal_orientation pose: largest angle of the rotation between the goal '
                  'orientation and the reached one that counts as met, rad',
                  bounds=(1e-12, 3.2)),
    ParameterSpec('start_limit_margin', 0.05,
                  'a start joint this far outside its limits (rad) is planned from, the motion '
                  'bringing it inside, with a warning; further out the goal is refused',
                  bounds=(0.0, 3.2)),
    ParameterSpec('base_frame', 'base_link', 'frame_id of the returned tool path'),
    ParameterSpec('sample_period', 0.1, 'time between trajectory points, s',
                  bounds=(1e-3, 10.0)),
    ParameterSpec('max_planning_time', 1.0,
                  'longest a plan may search, s; past it the plan ends as timed_out',
                  bounds=(1e-3, 60.0)),
    ParameterSpec('execution', 'topic',
                  'how a planned motion reaches the controller: topic (published on '
                  'joint_trajectory), action (a FollowJointTrajectory goal to '
                  'controller_action, with its result on plan_results; needs '
                  'control_msgs) or none (planned and answered, never sent)',
                  choices=('topic', 'action', 'none')),
    ParameterSpec('controller_action', CONTROLLER_ACTION,
                  "execution action: the controller's FollowJointTrajectory action; a relative "
                  "name is in the node's namespace and remapping applies, an absolute one such "
                  'as /arm_controller/follow_joint_trajectory is used as it is'),
    ParameterSpec('transform_timeout', 0.5,
                  'how long a stamped goal waits for its frame from tf (tf2 needed for frames '
                  "outside the arm's URDF), s; the newest transform for a stamp of zero",
                  bounds=(0.0, 60.0)),
    ParameterSpec('start_tolerance', 0.05,
                  "execution action: largest difference between a plan's start and the newest "
                  'joint_states, per joint, for the motion to be sent, rad; 0: not checked',
                  bounds=(0.0, 3.2)),
    ParameterSpec('controller_timeout', 5.0,
                  'execution action: how long the controller may take to appear and to answer '
                  "a goal, and to finish past the motion's duration, s", bounds=(0.01, 600.0)),
    ParameterSpec('max_trajectory_points', 10000,
                  'most points a published trajectory may have; a plan needing more is refused',
                  bounds=(2, 50000)),
    ParameterSpec('diagnostic_updater.period', 1.0,
                  'period of /diagnostics, s (read at start-up)', bounds=(0.1, 3600.0)),
    ParameterSpec('max_queued_calls', 1000,
                  'most service calls that may wait for a plan; more are answered at once with '
                  'an empty plan', bounds=(1, 100000)),
    ParameterSpec('min_planning_time', 0.0,
                  'plan_kinematic_path: least search time a MoveIt request gets, s; a shorter '
                  'allowed_planning_time is raised to it (said once); 0: as asked',
                  bounds=(0.0, 600.0)),
    ParameterSpec('moveit_interfaces', False,
                  "serve move_group's plan_kinematic_path (moveit_msgs/srv/GetMotionPlan) for "
                  'MoveIt clients; needs moveit_msgs (read at start-up)'),
)


def default_values() -> dict[str, Any]:
    """Every parameter's default, by name."""
    return {spec.name: spec.default for spec in PARAMETERS}


@dataclass(frozen=True)
class Settings:
    """The planning settings in force, built from (and checked against) the node's parameters."""

    #: The plan's settings from the parameters (goal and start are each job's).
    request: PlanRequest
    base_frame: str
    sample_period: float
    start: np.ndarray
    max_trajectory_points: int
    max_queued_calls: int
    diagnostic_period: float
    #: The URDF the arm was built from ('' for the DH parameters).
    description: str = ''
    #: start_positions did not fit the described chain and all zeros stand in for it.
    start_ignored: bool = False
    #: How a pose goal's orientation is used: 'ignore', 'approach' (its z axis) or 'pose'.
    goal_orientation: str = 'ignore'
    #: How a planned motion reaches the controller: 'topic', 'action' or 'none'.
    execution: str = 'topic'
    #: execution action: the controller's action, as given (the node resolves it).
    controller_action: str = CONTROLLER_ACTION
    #: execution action: the largest start difference to joint_states, rad (0: unchecked).
    start_tolerance: float = 0.05
    #: execution action: how long the controller may take, s.
    controller_timeout: float = 5.0
    #: plan_kinematic_path: the least search time a MoveIt request gets, s (0: as asked).
    min_planning_time: float = 0.0
    #: How long a stamped goal waits for its frame's transform from tf, s.
    transform_timeout: float = 0.5

    @property
    def arm(self) -> ArmModel:
        """Return the arm planned for."""
        return self.request.planned_arm

    @property
    def world(self) -> CollisionWorld | None:
        """Return the collision model, the scene_file's obstacles and the padding (or None)."""
        return self.request.world

    @functools.cached_property
    def frames(self) -> RobotFrames:
        """Return the robot's link frames: a goal may be in any of them (or in base_frame)."""
        return _frames(_urdf(self.description, self.arm).encode(), self.arm.base_link)

    def planning_with(self, **changes: Any) -> Settings:
        """Return these settings with ``changes`` to the plan's (``PlanRequest``'s fields)."""
        return replace(self, request=self.request.replace(**changes))

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any], topic_description: str = '',
                        strict_start: bool = True, topic_semantic: str = '') -> Settings:
        """
        Raise ValueError (InvalidArmModel for the arm) with the reason a value is refused.

        ``topic_description``, ``topic_semantic``: the last URDF and SRDF received on the
        robot_description and robot_description_semantic topics. With ``strict_start`` False,
        a ``start_positions`` that does not fit a described chain gives all zeros instead of a
        refusal (``start_ignored`` says so).
        """
        description = values['robot_description'] or topic_description
        if description:
            arm = _urdf_arm(description.encode(), values['base_link'] or None,
                            values['tip_link'] or None, tuple(values['tool_offset']),
                            tuple(values['tool_axis']))
        else:
            arm = ArmModel.from_dh(*(values[f'arm.{k}'] for k in ('a', 'alpha', 'd')),
                                   sign=values['arm.sign'], offset=values['arm.offset'],
                                   lower=values['arm.lower'], upper=values['arm.upper'],
                                   joint_names=list(values['arm.joint_names']),
                                   planned=values['arm.planned'])
        for spec in PARAMETERS:
            if spec.choices and values[spec.name] not in spec.choices:
                raise ValueError(f"{spec.name} must be one of {', '.join(spec.choices)}, "
                                 f'got {values[spec.name]!r}')
        for name in ('base_frame', 'controller_action'):
            if not values[name]:
                raise ValueError(f'{name} must not be empty')
        start_positions, base_frame = values['start_positions'], values['base_frame']
        defaults = default_values()
        zeros = np.clip(np.zeros(arm.n_joints), arm.lower, arm.upper)
        ignored = bool(description) and not strict_start and len(start_positions) not in (
            arm.n_joints, arm.planned)
        if description and (list(start_positions) == defaults['start_positions'] or ignored):
            start_positions = zeros
        if description and base_frame == defaults['base_frame']:
            base_frame = arm.base_link
        try:
            start = arm.full_start(start_positions)
        except ValueError as exc:
            raise ValueError(f'start_positions: {exc} for the {arm.n_joints}-joint arm '
                             '(change both at once)') from None
        if not np.all(np.isfinite(start)):
            raise ValueError(f'start_positions has a non-finite angle: {start.tolist()}')
        request = _request(values, arm)
        request = request.replace(world=_world(values, arm, description, topic_semantic))
        return cls(request=request, base_frame=base_frame, description=description,
                   start_ignored=ignored, sample_period=values['sample_period'], start=start,
                   max_trajectory_points=values['max_trajectory_points'],
                   max_queued_calls=values['max_queued_calls'],
                   goal_orientation=values['goal_orientation'],
                   execution=values['execution'],
                   controller_action=values['controller_action'],
                   start_tolerance=values['start_tolerance'],
                   controller_timeout=values['controller_timeout'],
                   min_planning_time=values['min_planning_time'],
                   transform_timeout=values['transform_timeout'],
                   diagnostic_period=values['diagnostic_updater.period'])


def _request(values: Mapping[str, Any], arm: ArmModel) -> PlanRequest:
    """Return the plan settings of the parameters, checked: all but the world, start and point."""
    base = (_limits_file(values['joint_limits_file']) if values['joint_limits_file']
            else MotionProfile())
    motion = replace(base, profile=values['profile'], timing=values['timing'],
                     max_acceleration=values['max_acceleration'] or None,
                     max_jerk=values['max_jerk'] or None,
                     velocity_scaling=values['velocity_scaling'] or base.velocity_scaling,
                     acceleration_scaling=(values['acceleration_scaling']
                                           or base.acceleration_scaling))
    mode = Mode.APPROACH.value if values['goal_orientation'] == 'approach' else values['mode']
    goal = Goal(mode=mode, approach=values['approach_direction'], tolerance=values['tolerance'],
                axis_tolerance=values['axis_tolerance'] or None,
                orientation_tolerance=values['orientation_tolerance'])
    request = PlanRequest(
        goal, arm=arm, motion=motion, angular_velocity=values['angular_velocity'],
        algorithm=values['algorithm'],
        population=values['population'], max_iterations=values['max_iterations'],
        seed=None if values['seed'] < 0 else values['seed'],
        max_planning_time=values['max_planning_time'],
        start_limit_margin=values['start_limit_margin'], detours=values['detours'])
    request.validate()
    return request


@functools.lru_cache(maxsize=4)
def _urdf_arm(description: bytes, base_link: str | None, tip_link: str | None,
              tool_offset: tuple[float, ...], tool_axis: tuple[float, ...]) -> ArmModel:
    """
    Return the chain of a URDF, parsed once per text and settings (every check asks).

    The description is passed as bytes: always the document, never a file path.
    """
    return ArmModel.from_urdf(description, base_link, tip_link, tool_offset=tool_offset,
                              tool_axis=tool_axis)


def _world(values: Mapping[str, Any], arm: ArmModel, description: str,
           topic_semantic: str) -> CollisionWorld | None:
    """Return the collision world the parameters ask for (None: collision_check is off)."""
    if not values['collision_check']:
        return None
    urdf = _urdf(description, arm)
    model = _collision_model(urdf.encode(), arm.base_link, arm.tip_link,
                             values['robot_description_semantic'] or topic_semantic)
    scene = _scene(values['scene_file']) if values['scene_file'] else Scene()
    return CollisionWorld(model, scene, values['padding'])


@functools.lru_cache(maxsize=2)
def _collision_model(urdf: bytes, base_link: str, tip_link: str, srdf: str) -> ArmCollision:
    """
    Return the collision model of a URDF's chain, built once per URDF, chain and SRDF.

    Meshes come from package:// URIs through the ament index; no SRDF ('') computes the pairs
    to skip.
    """
    return ArmCollision.from_urdf(urdf, ArmModel.from_urdf(urdf, base_link, tip_link),
                                  meshes=MeshSource(get_package_share_directory),
                                  srdf=srdf or None)


def _urdf(description: str, arm: ArmModel) -> str:
    """Return the arm's URDF: its description, or one written from the DH parameters."""
    return description or urdf_xml(arm, velocity=DEFAULT_OMEGA)


@functools.lru_cache(maxsize=4)
def _frames(urdf: bytes, base_link: str) -> RobotFrames:
    """Return a URDF's link frames, read once per URDF and base."""
    return RobotFrames(urdf, base_link)


@functools.lru_cache(maxsize=4)
def _scene(path: str) -> Scene:
    """Return a scene file's obstacles, read once per path (as ``_joint_limits``)."""
    return Scene.from_file(path)


@functools.lru_cache(maxsize=4)
def _limits_file(path: str) -> MotionProfile:
    """
    Return a joint_limits.yaml's limits and default scalings, read once per path.

    (ValueError, not cached, if bad.) So a parameter change that leaves ``joint_limits_file``
    as it is does not read the file again; to read an edited file, set the parameter to
    another path (or empty) and back.
    """
    return MotionProfile.from_file(path)
