# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
One job of the planner node's worker: plan a goal, and for a call build the answer's path.

Pure translation between the planning core and ROS messages, no node: the worker thread calls
``run`` and then answers, publishes and logs what it returns.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable, Mapping, Sequence

from nav_msgs.msg import Path
import numpy as np
from std_msgs.msg import Header
from trajplan_ros.collision.free_motion import colliding_pairs
from trajplan_ros.planning import Goal, Mode, plan, PlanResult, PlanStatus, Trajectory
from trajplan_ros.planning.planner import describe_goal
from trajplan_ros.ros.joint_states import PlanStart
from trajplan_ros.ros.mailbox import Job
from trajplan_ros.ros.messages import path_msg
from trajplan_ros.ros.settings import Settings


__all__ = ['FramePose', 'Outcome', 'describe_arm', 'in_base', 'message_goal',
           'rotation_problem', 'run']

#: The 4x4 pose of a frame in the base frame (ValueError: it cannot be had).
FramePose = Callable[[str], np.ndarray]


def describe_arm(settings: Settings) -> str:
    """Write the arm in use and, for a URDF, which settings it overrides (the node logs it)."""
    arm = settings.arm
    joints = f"{arm.n_joints}-joint arm ({', '.join(arm.joint_names)})"
    if not settings.description:
        return f'{joints} from the arm.* DH parameters'
    return (f'{joints} from robot_description, chain {arm.base_link} -> {arm.tip_link}, '
            f"frame '{settings.base_frame}': the arm.* parameters are ignored, every chain "
            'joint is planned, start_positions must list these joints')


@dataclass
class Outcome:
    """What a job came to: the messages to send (on success) and the log line."""

    succeeded: bool
    log: str
    status: str                              # PlanStatus's value, or 'refused'
    reason: str                              # the plan's message, for the caller
    path: Path | None = None                 # built at once for a call: it is the answer
    trajectory: Trajectory | None = None     # converted when published, after the answer
    settings: Settings | None = None         # the settings it was planned with
    plan_time_s: float | None = None
    timed_out: bool = False                  # ended at max_planning_time
    motion_time_s: float | None = None       # of a published trajectory
    clearance: tuple[float, str] | None = None   # least clearance (m) and where (collisions)
    via_points: int | None = None            # via points of a published trajectory
    start: np.ndarray | None = None          # the joint angles it was planned from
    result: PlanResult | None = None         # the planning core's result, if it planned
    start_collides: str = ''                 # the pairs in collision at a refused start
    frame_failed: bool = False               # refused: the goal's frame could not be posed


def _refusal(where: str, result: PlanResult, took: str) -> str:
    optimised = f'; {took}' if result.joint_goal is not None else ''
    return f'{where}: {result.status.value}: {result.message}{optimised}'


def _describe_joints(joint_goal: np.ndarray | Mapping[str, float]) -> str:
    """Write a joint goal for the log: its angles, or its angles by name."""
    if isinstance(joint_goal, Mapping):
        return '{' + ', '.join(f'{name}: {angle:.6g}' for name, angle in joint_goal.items()) + '}'
    return describe_goal(joint_goal)


def rotation_problem(orientation: Sequence[float]) -> str | None:
    """Return why a quaternion (x, y, z, w) is not a rotation, or None."""
    if all(map(math.isfinite, orientation)) and any(orientation):
        return None
    return f'the goal orientation {list(orientation)} is not a rotation (x, y, z, w)'


def message_goal(settings: Settings, position: Sequence[float], frame: str = '',
                 orientation: Sequence[float] | None = None,
                 tolerance: float | None = None) -> Goal:
    """
    Return the goal of a topic message or a GetPlan call, in its frame.

    Its point, and a pose's orientation as ``goal_orientation`` says (ignored; the tool axis
    along its z axis; or the whole pose); the kind and tolerances the parameters give, a
    call's positive ``tolerance`` instead of theirs.
    """
    template = settings.request.goal
    goal = template.replace(position=position, frame=frame,
                            tolerance=tolerance or template.tolerance)
    how = settings.goal_orientation
    if how == 'ignore' or orientation is None:
        return goal
    q = np.asarray(orientation, dtype=float)
    if rotation_problem(orientation) is None:          # else kept as given, to be refused
        q = q / np.linalg.norm(q)
    return goal.replace(mode=Mode.POSE if how == 'pose' else Mode.APPROACH, orientation=q)


def in_base(goal: Goal, settings: Settings, pose_of: FramePose) -> Goal:
    """Return ``goal`` in the base frame, ``pose_of`` posing its frame there (ValueError)."""
    if goal.frame in ('', settings.base_frame):
        return goal.replace(frame='')
    return goal.moved(pose_of(goal.frame))


def run(job: Job, settings: Settings, start: PlanStart, header: Header,
        stop: Callable[[], bool], pose_of: FramePose) -> Outcome:
    """
    Plan ``job`` from ``start``; on success build its trajectory and tool path messages.

    A goal in another frame is brought into the base frame first, ``pose_of`` posing the frame
    (``job.goal`` then holds it); a frame that cannot be posed refuses the job.
    """
    s = settings
    given = job.goal
    try:
        job.goal = goal = in_base(given, s, pose_of)
    except ValueError as exc:
        return Outcome(False, f'{job.label} {describe_goal(given.position)} m: refused: {exc}',
                       'refused', str(exc), start=start.q, frame_failed=True)
    request = s.request.replace(goal=goal, start=start.q, **job.request_changes)
    if goal.joint_goal is not None:
        what = f'{job.label} to joint goal {_describe_joints(goal.joint_goal)} rad'
    else:
        moved = (f" (in '{given.frame}': {describe_goal(given.position)} m)"
                 if given.frame not in ('', s.base_frame) else '')
        what = f'{job.label} {describe_goal(goal.position)} m{moved}'
    where = f'{what} from q = {describe_goal(start.q)} rad{start.describe()}'
    touching = (colliding_pairs(s.world, start.q)
                if job.start_must_be_free and s.world is not None else '')
    if touching:
        reason = f'the start is in collision: {touching}'
        return Outcome(False, f'{where}: refused: {reason}', 'refused', reason, start=start.q,
                       start_collides=touching)
    result = plan(request, stop=stop)
    if goal.joint_goal is not None and result.joint_goal is not None:
        job.goal = goal.replace(position=result.goal)    # the tool point there, for the log
    took = f'planned in {1e3 * result.plan_time_s:.3f} ms'
    clearance = (result.clearance_m, result.clearance_pair) if result.clearance_pair else None
    timed = result.plan_time_s if result.joint_goal is not None else None
    if not result.success:
        return Outcome(False, _refusal(where, result, took), result.status.value,
                       result.message, plan_time_s=timed,
                       timed_out=result.status is PlanStatus.TIMED_OUT, clearance=clearance,
                       start=start.q, result=result)
    points = result.trajectory_points(sample_period=s.sample_period)
    if points > s.max_trajectory_points:
        reason = (f'the trajectory would need {points} points, more than '
                  f'max_trajectory_points {s.max_trajectory_points} (motion '
                  f'{result.motion_time_s:.3f} s at sample_period {s.sample_period:g} s)')
        return Outcome(False, f'{where}: refused: {reason}; {took}', 'refused', reason,
                       plan_time_s=timed, start=start.q, result=result)
    traj = result.trajectory(sample_period=s.sample_period)
    path = path_msg(s.arm, traj, header) if job.is_call and job.answer_path else None
    sent = ('answered, not sent (plan only)' if job.plan_only else
            {'topic': 'published', 'action': 'sending', 'none': 'not sent (execution none):'}[
                s.execution])
    return Outcome(True, f'{where}: {result.message}; {took}; {sent} {len(traj.times)} '
                         f'points over {traj.duration:.3f} s', result.status.value,
                   result.message, path=path, trajectory=traj, settings=s,
                   plan_time_s=timed, motion_time_s=result.motion_time_s, clearance=clearance,
                   via_points=len(result.via_points), start=start.q, result=result)
