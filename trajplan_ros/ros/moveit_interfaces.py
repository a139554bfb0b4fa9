# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
move_group's requests and answers, translated to and from the node's jobs (no node here).

A MotionPlanRequest becomes one job per goal region (``goal_jobs``), planned in turn with the
node's other calls; the fastest region's outcome becomes the response (``fastest``,
``fill_response``): the joint trajectory from the start, and a MoveItErrorCodes whose message
is the planner's reason. ``ik_job`` and ``fk_poses`` serve compute_ik and compute_fk;
``execution_motion`` an ExecuteTrajectory goal.

A region is one ``Constraints``: a PositionConstraint on the tip link, whose region (a sphere,
or a box's inscribed sphere) is the position tolerance, and the plan is the least-time motion
into it, not to its centre (``search.region``). An OrientationConstraint beside it makes the
goal a pose (its least tolerance the orientation tolerance), or, with the z tolerance pi or
more, an approach goal (the tool's z axis within the lesser of the x and y tolerances of the
orientation's z axis); all three pi or more: position only. JointConstraints instead are a
joint goal: the motion to those angles (``Goal.joint_goal``). What a direct motion
cannot promise (path constraints, visibility constraints) is refused with the reason, never
ignored. moveit_msgs is not on PyPI: ``moveit_types`` says how to get it.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Any, Callable

from defusedxml import ElementTree
import numpy as np
from rclpy.task import Future
from trajplan_ros.kinematics.rotations import rotation_matrix
from trajplan_ros.planning import Goal, Mode, PlanStatus
from trajplan_ros.ros.execution import Motion
from trajplan_ros.ros.job import Outcome, rotation_problem
from trajplan_ros.ros.mailbox import Job
from trajplan_ros.ros.messages import trajectory_msg
from trajplan_ros.ros.settings import Settings
from trajplan_ros.ros.transforms import frame_problem

__all__ = ['EXECUTION_CODES', 'HOW_TO', 'SOURCE', 'Refusal', 'error_code', 'execution_motion',
           'fastest', 'fill_response', 'fk_poses', 'goal_jobs', 'ik_job', 'moveit_types',
           'srdf_groups']

#: The error code's source, as move_group names its own.
SOURCE = 'trajplan_ros'
#: How to get moveit_msgs on each route.
HOW_TO = ('with ROS from apt: sudo apt install ros-jazzy-moveit-msgs; with the PyPI wheels: '
          'build ../shared/ros_interfaces with its build_ros_interfaces.sh (moveit_msgs) and '
          'put the printed PYTHONPATH and LD_LIBRARY_PATH in the environment')
#: MoveIt's fields that choose among its planners: read, logged once, not used.
IGNORED = ('planner_id', 'pipeline_id', 'num_planning_attempts', 'workspace_parameters')
_FREE = math.pi                       # a tolerance this large leaves the rotation free


def moveit_types() -> Any:
    """Return moveit_msgs' modules (msg, srv); ValueError with how to get it if it fails."""
    try:
        from moveit_msgs import msg, srv
        from rclpy.type_support import check_for_type_support

        check_for_type_support(srv.GetMotionPlan)
    except Exception as exc:  # noqa: BLE001 - not installed, or its C libraries do not load
        raise ValueError(f'moveit_interfaces needs moveit_msgs, which does not load here '
                         f'({type(exc).__name__}: {str(exc).splitlines()[0]}): '
                         f'{HOW_TO}') from None
    return msg, srv


class Refusal(ValueError):
    """A request refused before planning: MoveItErrorCodes' name of the code, and why."""

    def __init__(self, code: str, reason: str) -> None:
        super().__init__(reason)
        self.code = code


def srdf_groups(srdf: str) -> tuple[str, ...]:
    """Return the names of an SRDF's planning groups (none for an empty or broken SRDF)."""
    if not srdf:
        return ()
    try:
        root = ElementTree.fromstring(srdf)
    except Exception:  # noqa: BLE001 - untrusted text: a broken SRDF names no group
        return ()
    return tuple(g.get('name', '') for g in root.iter('group'))


def goal_jobs(label: str, request: Any, settings: Settings, srdf: str,
              ignored: Callable[[str], None], with_tf: bool = False) -> list[Job]:
    """
    Return the jobs of a MotionPlanRequest, one per goal region (Refusal: why, and the code).

    ``srdf``: the semantic description in use (its groups name the group); ``ignored`` is told
    each of MoveIt's planner-choosing fields that is set (``IGNORED``), and
    ``allowed_planning_time`` where ``min_planning_time`` raises it. ``with_tf``: a frame
    outside the URDF may come through tf. Each job is a call with a future of its own; the
    fastest region's plan is the answer (``fastest``).
    """
    s = settings
    _check_group(request.group_name, srdf)
    for name in IGNORED[:3]:
        if getattr(request, name):
            ignored(name)
    if request.workspace_parameters.header.frame_id:
        ignored('workspace_parameters')
    if _has_constraints(request.path_constraints):
        raise Refusal('PLANNING_FAILED', 'path constraints are not offered: a direct motion '
                                         'cannot promise them along the way')
    if not request.goal_constraints:
        raise Refusal('INVALID_GOAL_CONSTRAINTS', 'no goal constraints given')
    start = _start_state(request.start_state, s)
    scale = {f'{kind}_scaling': factor for kind, factor in (
        ('velocity', request.max_velocity_scaling_factor),
        ('acceleration', request.max_acceleration_scaling_factor)) if 0.0 < factor <= 1.0}
    count = len(request.goal_constraints)        # the regions share the time (searched in turn)
    budget = _budget(request.allowed_planning_time, 'allowed_planning_time', s, ignored) / count
    jobs = []
    for k, goal in enumerate(request.goal_constraints):
        named = label if count == 1 else f'{label} region {k + 1}/{count}'
        if goal.visibility_constraints:
            raise Refusal('INVALID_GOAL_CONSTRAINTS', 'visibility constraints are not offered')
        job = (_joint_goal_job(named, goal, s, Future(), start) if goal.joint_constraints
               else _tip_goal_job(named, goal, s, Future(), start, with_tf))
        changes: dict[str, Any] = {}
        if scale:                                 # MoveIt's rule: any other factor means 1
            changes['motion'] = dataclasses.replace(s.request.motion, **scale)
        changes['max_planning_time'] = budget
        job.request_changes = changes
        job.start_must_be_free = True
        jobs.append(job)
    return jobs


def fastest(outcomes: list[Outcome | None], jobs: list[Job]) -> tuple[int, tuple[str, str]]:
    """
    Return which region's outcome answers a request, and its code: the least motion time.

    With no region planned, the first region's code (``error_code``).
    """
    codes = [error_code(outcome, job) for outcome, job in zip(outcomes, jobs)]
    done = [k for k, code in enumerate(codes) if code[0] == 'SUCCESS']
    if not done:
        return 0, codes[0]
    best = min(done, key=lambda k: outcomes[k].result.motion_time_s)
    return best, codes[best]


def _budget(asked: float, name: str, settings: Settings,
            ignored: Callable[[str], None]) -> float:
    """Return a request's time budget: as asked if positive, at least min_planning_time."""
    budget = asked if 0.0 < asked < math.inf else settings.request.max_planning_time
    if budget < settings.min_planning_time:
        ignored(name)
        budget = settings.min_planning_time
    return float(budget)


def ik_job(label: str, ik: Any, settings: Settings, srdf: str,
           ignored: Callable[[str], None], with_tf: bool = False) -> Job:
    """
    Return the job of a PositionIKRequest: the tip link's pose, planned from the seed state.

    Its answer is the joint goal the planner would move to (Refusal: why it is refused).
    """
    s = settings
    _check_group(ik.group_name, srdf)
    if _has_constraints(ik.constraints):
        raise Refusal('INVALID_GOAL_CONSTRAINTS', 'constraints on an IK request are not '
                                                  'offered: the pose is solved as given')
    start = _start_state(ik.robot_state, s)
    _check_link(ik.ik_link_name, s)
    frame = _frame(ik.pose_stamped.header.frame_id, s, with_tf)
    p, o = ik.pose_stamped.pose.position, ik.pose_stamped.pose.orientation
    q = (o.x, o.y, o.z, o.w)
    problem = rotation_problem(q)
    if problem:
        raise Refusal('INVALID_GOAL_CONSTRAINTS', problem)
    # the pose is the link's origin's; the planner places its tool point (tool_offset)
    unit = np.asarray(q) / np.linalg.norm(q)
    point = np.array([p.x, p.y, p.z]) + rotation_matrix(unit) @ s.arm.tool_point
    goal = s.request.goal.replace(position=point, frame=frame, mode=Mode.POSE, orientation=unit)
    stamp = ik.pose_stamped.header.stamp
    job = Job(label, goal, future=Future(), plan_only=True, start_state=start,
              answer_path=False, stamp=(stamp.sec, stamp.nanosec))
    timeout = ik.timeout.sec + 1e-9 * ik.timeout.nanosec
    job.request_changes = {'max_planning_time': _budget(timeout, 'timeout', s, ignored)}
    if not ik.avoid_collisions:
        job.request_changes['world'] = None
    return job


def fk_poses(request: Any, settings: Settings, now: dict[str, float]) -> list[np.ndarray]:
    """
    Return the 4x4 poses of a GetPositionFK request's links in its frame (Refusal: why not).

    The joint angles are the request's robot state's, those it does not name ``now``'s.
    """
    angles = {**now, **_named_angles(request.robot_state, 'robot_state')}
    frame = _frame(request.header.frame_id, settings)
    into = np.linalg.inv(settings.frames.to_base(frame, angles))
    poses = []
    for link in request.fk_link_names:
        problem = _urdf_problem(link, settings) if link else 'an empty link name'
        if problem:
            raise Refusal('INVALID_LINK_NAME', problem)
        poses.append(into @ settings.frames.to_base(link, angles))
    return poses


def _tip_goal_job(label: str, goal: Any, settings: Settings, future: Any,
                  start: dict[str, float], with_tf: bool) -> Job:
    """Return the job of a position (and orientation) goal on the tip."""
    if len(goal.position_constraints) != 1 or len(goal.orientation_constraints) > 1:
        raise Refusal('INVALID_GOAL_CONSTRAINTS',
                      f'{len(goal.position_constraints)} position and '
                      f'{len(goal.orientation_constraints)} orientation constraints given: one '
                      'position constraint is planned, with at most one orientation constraint')
    position = goal.position_constraints[0]
    _check_link(position.link_name, settings)
    frame = _frame(position.header.frame_id, settings, with_tf)
    centre, radius = _region(position)
    region = Goal(centre, tolerance=radius, frame=frame)
    if goal.orientation_constraints:
        region = _oriented(region, goal.orientation_constraints[0], settings)
    _check_offset(position, settings)
    stamp = position.header.stamp
    return Job(label, region, future=future, plan_only=True, start_state=start,
               answer_path=False, stamp=(stamp.sec, stamp.nanosec))


def _joint_goal_job(label: str, goal: Any, settings: Settings, future: Any,
                    start: dict[str, float]) -> Job:
    """
    Return the job of a goal of JointConstraints: the chain's joints they name, at their position.

    A position beyond a limit by no more than its tolerance is taken at the limit; joints not
    named keep their start.
    """
    if goal.position_constraints or goal.orientation_constraints:
        raise Refusal('INVALID_GOAL_CONSTRAINTS', 'joint constraints beside a position or '
                                                  'orientation constraint: give one kind')
    arm = settings.arm
    angles = {}
    for c in goal.joint_constraints:
        if c.joint_name not in arm.joint_names:
            raise Refusal('INVALID_GOAL_CONSTRAINTS', f"joint constraint on '{c.joint_name}': "
                                                      'this node plans the chain '
                                                      f"{', '.join(arm.joint_names)}")
        i = arm.joint_names.index(c.joint_name)
        values = (c.position, c.tolerance_above, c.tolerance_below)
        if not (all(map(math.isfinite, values)) and min(values[1:]) >= 0.0):
            raise Refusal('INVALID_GOAL_CONSTRAINTS', f'joint constraint on {c.joint_name}: '
                                                      f'position {c.position}, tolerances '
                                                      f'{c.tolerance_above}, {c.tolerance_below}')
        low, high = arm.lower[i], arm.upper[i]
        q = c.position               # met within [q - below, q + above]: a limit may lie there
        if low - c.tolerance_above <= q <= high + c.tolerance_below:
            q = min(max(q, low), high)
        angles[c.joint_name] = float(q)
    return Job(label, Goal(joint_goal=angles), future=future, plan_only=True,
               start_state=start, answer_path=False)


def _has_constraints(constraints: Any) -> bool:
    return bool(constraints.joint_constraints or constraints.position_constraints
                or constraints.orientation_constraints or constraints.visibility_constraints)


def _start_state(state: Any, settings: Settings) -> dict[str, float]:
    """Return the planned joints' angles a RobotState gives (the others come from the node)."""
    given = _named_angles(state, 'start_state')
    arm = settings.arm
    margin = settings.request.start_limit_margin         # as the node's own start is held
    start = {}
    for name, low, high in zip(arm.joint_names, arm.lower, arm.upper):
        if name not in given:
            continue
        q = given[name]
        if not low - margin <= q <= high + margin:            # finite: _named_angles
            raise Refusal('INVALID_ROBOT_STATE', f'start_state: {name} = {q} rad is outside '
                                                 f'its limits [{low:g}, {high:g}]')
        start[name] = q
    return start


def _check_group(group: str, srdf: str) -> None:
    """Refuse a group the SRDF in use does not name (any group without an SRDF)."""
    groups = srdf_groups(srdf)
    if group and groups and group not in groups:
        raise Refusal('INVALID_GROUP_NAME', f"group '{group}' is not in the SRDF "
                                            f"(groups: {', '.join(groups)})")


def _named_angles(state: Any, what: str) -> dict[str, float]:
    """Return a RobotState's joint angles by name (Refusal: lengths differ, or not finite)."""
    names, positions = list(state.joint_state.name), list(state.joint_state.position)
    if len(names) != len(positions):
        raise Refusal('INVALID_ROBOT_STATE', f'{what} has {len(names)} joint names and '
                                             f'{len(positions)} positions')
    given = dict(zip(names, map(float, positions)))
    bad = [n for n, q in given.items() if not math.isfinite(q)]
    if bad:
        raise Refusal('INVALID_ROBOT_STATE', f'{what}: {bad[0]} = {given[bad[0]]} is not finite')
    return given


def _check_link(link: str, settings: Settings) -> None:
    tip = settings.arm.tip_link or 'the tool'
    if link and link != settings.arm.tip_link:
        raise Refusal('INVALID_LINK_NAME', f"constraints on link '{link}': this node plans "
                                           f"the tip link '{tip}'")


def _urdf_problem(frame: str, settings: Settings) -> str | None:
    """Return why ``frame`` is not the base or a link of the URDF, or None."""
    try:
        settings.frames.check(frame)
    except ValueError as exc:
        return str(exc)
    return None


def _frame(frame: str, settings: Settings, with_tf: bool | None = None) -> str:
    """Return a request's frame (Refusal: one it cannot pose; None: a URDF link, not tf's)."""
    problem = (_urdf_problem(frame, settings) if with_tf is None
               else frame_problem(frame, settings, with_tf))
    if problem:
        raise Refusal('FRAME_TRANSFORM_FAILURE', problem)
    return frame


def _region(position: Any) -> tuple[np.ndarray, float]:
    """Return a PositionConstraint's region as a ball: its centre (its frame) and radius, m."""
    volume = position.constraint_region
    if volume.meshes:
        raise Refusal('INVALID_GOAL_CONSTRAINTS', 'a mesh region is not offered: give a '
                                                  'sphere or a box')
    if len(volume.primitives) != 1:
        raise Refusal('INVALID_GOAL_CONSTRAINTS', f'{len(volume.primitives)} primitives in '
                                                  'the position region; one is planned')
    shape = volume.primitives[0]
    dims = list(shape.dimensions)
    if shape.type == shape.SPHERE and len(dims) >= 1:
        radius = dims[0]
    elif shape.type == shape.BOX and len(dims) >= 3:
        radius = min(dims[:3]) / 2                   # the box's inscribed ball
    else:
        raise Refusal('INVALID_GOAL_CONSTRAINTS', f'position region of type {shape.type} with '
                                                  f'dimensions {dims}: a sphere or a box is '
                                                  'planned')
    if not (math.isfinite(radius) and radius > 0.0):
        raise Refusal('INVALID_GOAL_CONSTRAINTS', f'position region of size {radius}')
    p = volume.primitive_poses[0].position if volume.primitive_poses else None
    centre = np.array([p.x, p.y, p.z] if p is not None else [0.0, 0.0, 0.0])
    if not np.all(np.isfinite(centre)):
        raise Refusal('INVALID_GOAL_CONSTRAINTS', f'position region at {centre.tolist()}')
    return centre, float(radius)


def _oriented(region: Goal, constraint: Any, settings: Settings) -> Goal:
    """Return the position region as a pose or approach goal as an OrientationConstraint says."""
    _check_link(constraint.link_name, settings)
    base = settings.base_frame
    if (constraint.header.frame_id or base) != (region.frame or base):
        raise Refusal('INVALID_GOAL_CONSTRAINTS', 'the position and orientation constraints '
                                                  'are in different frames')
    o = constraint.orientation
    q = (o.x, o.y, o.z, o.w)
    problem = rotation_problem(q)
    if problem:
        raise Refusal('INVALID_GOAL_CONSTRAINTS', problem)
    tol = [constraint.absolute_x_axis_tolerance, constraint.absolute_y_axis_tolerance,
           constraint.absolute_z_axis_tolerance]
    if not all(math.isfinite(t) and t > 0.0 for t in tol):
        raise Refusal('INVALID_GOAL_CONSTRAINTS', f'orientation tolerances {tol}: each must '
                                                  'be positive')
    free = [t >= _FREE for t in tol]
    if all(free):
        return region
    unit = np.asarray(q) / np.linalg.norm(q)
    if free[2] and not any(free[:2]):
        return region.replace(mode=Mode.APPROACH, orientation=unit, axis_tolerance=min(tol[:2]))
    if not any(free):
        return region.replace(mode=Mode.POSE, orientation=unit, orientation_tolerance=min(tol))
    raise Refusal('INVALID_GOAL_CONSTRAINTS', 'a rotation free about the x or y axis is not '
                                              'offered; free about z, it is an approach goal')


def _check_offset(position: Any, settings: Settings) -> None:
    """Refuse a target_point_offset that is not the node's tool point."""
    o = position.target_point_offset
    offset = np.array([o.x, o.y, o.z])
    tool = settings.arm.tool_point
    if not np.allclose(offset, tool, atol=1e-9):
        raise Refusal('INVALID_GOAL_CONSTRAINTS',
                      f'target_point_offset {offset.tolist()} m: this node plans the tool point '
                      f'{tool.tolist()} m in the tip link (the tool_offset parameter)')


def error_code(outcome: Outcome | None, job: Job) -> tuple[str, str]:
    """
    Return MoveItErrorCodes' name for the outcome of ``job``, and its message.

    A goal not reached is out of reach (NO_IK_SOLUTION) unless it asked an orientation and
    missed it (GOAL_CONSTRAINTS_VIOLATED: an arm of five joints asked a pose it cannot take;
    the message says how far the best one is), or every motion to it collides
    (PLANNING_FAILED). None: the node shut down before planning it.
    """
    if outcome is None:                       # not planned: shutting down, queue full, a fault
        status, reason = job.ended
        return ('PREEMPTED' if status == 'shut_down' else 'PLANNING_FAILED'), reason
    if outcome.succeeded:
        return 'SUCCESS', outcome.reason
    if outcome.start_collides:
        return 'START_STATE_IN_COLLISION', outcome.reason
    if outcome.frame_failed:
        return 'FRAME_TRANSFORM_FAILURE', outcome.reason
    result = outcome.result
    status = result.status if result is not None else None
    if status is PlanStatus.TIMED_OUT:
        return 'TIMED_OUT', outcome.reason
    if status is PlanStatus.CANCELLED:
        return 'PREEMPTED', outcome.reason
    if status is PlanStatus.REJECTED:
        inside = ('inside obstacle' in outcome.reason      # planner._check_world's words
                  or bool(result.clearance_pair))          # a joint goal's pose collides
        return ('GOAL_IN_COLLISION' if inside else 'INVALID_GOAL_CONSTRAINTS'), outcome.reason
    if status is PlanStatus.NOT_REACHED:
        if result.clearance_pair:                   # reached, but every motion collides
            return 'PLANNING_FAILED', outcome.reason
        goal = job.goal
        if goal.joint_goal is None and goal.mode in (Mode.APPROACH, Mode.POSE):
            angle = (result.orientation_error_rad if goal.mode is Mode.POSE
                     else result.axis_error_rad)
            if not angle <= goal.angle_limit:
                return 'GOAL_CONSTRAINTS_VIOLATED', outcome.reason
        return 'NO_IK_SOLUTION', outcome.reason
    return 'PLANNING_FAILED', outcome.reason


def fill_response(response: Any, outcome: Outcome | None, code: tuple[str, str],
                  settings: Settings, group: str, header: Any, codes: Any) -> Any:
    """Fill a MotionPlanResponse: the trajectory (on success), the start, the code and why."""
    name, message = code
    response.group_name = group
    response.error_code = codes(val=getattr(codes, name), message=message, source=SOURCE)
    arm = settings.arm
    if outcome is not None and outcome.start is not None:
        state = response.trajectory_start.joint_state
        state.header = header
        state.name = list(arm.joint_names)
        state.position = [float(q) for q in outcome.start]
    if outcome is not None and outcome.result is not None:
        response.planning_time = float(outcome.result.plan_time_s)
    if name == 'SUCCESS' and outcome.trajectory is not None:
        trajectory = trajectory_msg(outcome.trajectory)
        trajectory.header = header
        first = trajectory.points[0]
        if first.time_from_start.sec or first.time_from_start.nanosec:   # MoveIt's: the start
            rest = np.zeros(len(outcome.start))
            trajectory.points.insert(0, type(first)(
                positions=outcome.start.tolist(),
                velocities=rest.tolist() if len(first.velocities) else [],
                accelerations=rest.tolist() if len(first.accelerations) else []))
        response.trajectory.joint_trajectory = trajectory
    return response


#: How an executed motion's end (``ros.execution``'s status) reads as MoveIt's code.
EXECUTION_CODES = {'executed': 'SUCCESS', 'preempted': 'PREEMPTED', 'shut_down': 'PREEMPTED',
                   'cancelled': 'PREEMPTED', 'refused': 'INVALID_MOTION_PLAN',
                   'timed_out': 'TIMED_OUT'}


def execution_motion(job: Job, trajectory: Any, settings: Settings, action: str) -> Motion:
    """
    Return the motion of an ExecuteTrajectory goal's joint trajectory (Refusal: why not).

    Its joints must be the planned chain's (in any order), its times rising from its start.
    """
    names = list(trajectory.joint_names)
    arm = settings.arm
    if sorted(names) != sorted(arm.joint_names):
        raise Refusal('INVALID_MOTION_PLAN', f'the trajectory moves joints {names}; this node '
                                             f'executes the chain {list(arm.joint_names)}')
    points = trajectory.points
    times = [p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec for p in points]
    if not points or any(len(p.positions) != len(names) for p in points) or any(
            b < a for a, b in zip(times, times[1:])):
        raise Refusal('INVALID_MOTION_PLAN', 'the trajectory needs points with a position per '
                                             'joint at rising times')
    trajectory.header.stamp.sec = trajectory.header.stamp.nanosec = 0     # start it now
    return Motion(job, action, trajectory, dict(zip(names, map(float, points[-1].positions))),
                  [float(q) for q in points[0].positions], times[-1],
                  settings.controller_timeout, settings.start_tolerance)
