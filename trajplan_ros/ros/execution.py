# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Execution through the controller's FollowJointTrajectory action (parameter ``execution: action``).

Each planned motion is sent as a goal to the controller's action (parameter
``controller_action``, ``follow_joint_trajectory`` by default, e.g.
``/arm_controller/follow_joint_trajectory``), and what the controller makes of it goes to
``plan_results`` as the execution statuses of ``ros.outcomes``. rcl_action expands an action's
name in the node's namespace but applies no remapping rule, so the name is resolved here
(``resolve_action``) and the client gets it absolute. A motion passes through these states:

* waiting: planned, not yet sent, because no server is there yet (at most ``controller_timeout``
  s, then ``no_controller``) or no joint_states of its joints came yet (as long, then
  ``refused``), or a newer motion replaces it (``preempted``, never sent); when the server is
  there, a plan whose start is more than ``start_tolerance`` from the newest joint_states is
  ``refused``;
* sent: the goal is with the controller; no answer within ``controller_timeout`` s ends it as
  ``timed_out``; rejected: ``rejected``;
* accepted: executing; it ends with the controller's result (``executed``, or the result code's
  name with its ``error_string``), ``preempted`` (a newer motion cancels it, then is sent, as
  joint_trajectory_controller itself would), ``shut_down`` (cancelled at Ctrl-C), or
  ``timed_out`` (not finished ``controller_timeout`` s after the motion's duration: cancelled).

Every end carries the largest difference between joint_states and the planned goal, measured
``SETTLE_S`` after the controller's result (its last state travels apart from the result).
Concurrency: the worker thread hands motions over with ``submit`` (a deque and a guard
condition) and the main thread calls ``shut_down``; everything else, the action client and its
futures included, runs on the executor thread. control_msgs is imported only here, and only
when the node executes through the action (``action_type`` says how to get it).
"""
from __future__ import annotations

import collections
from dataclasses import dataclass
import functools
import math
import threading
import time
from typing import Any, Callable, Mapping, Sequence

from action_msgs.msg import GoalStatus
from rclpy.action import ActionClient
from rclpy.node import Node
from trajectory_msgs.msg import JointTrajectory
from trajplan_ros.ros.mailbox import Job
from trajplan_ros.ros.outcomes import Execution


__all__ = ['ActionExecution', 'action_type', 'Motion', 'position_error', 'resolve_action',
           'result_status', 'start_mismatch']
#: FollowJointTrajectory's Result.error_code values, by the status name they end in.
RESULT_CODES = {0: 'executed', -1: 'invalid_goal', -2: 'invalid_joints',
                -3: 'old_header_timestamp', -4: 'path_tolerance_violated',
                -5: 'goal_tolerance_violated'}
#: How often waiting motions and deadlines are looked at, s.
TICK_S = 0.05
#: How long after a result the joint error is measured: the controller's last joint_states
#: (50 Hz or more) travels apart from the result, and may come after it, s.
SETTLE_S = 0.05
#: How to get control_msgs, for a refusal of ``execution: action``.
HOW_TO = ('with ROS 2 from apt: sudo apt install ros-jazzy-control-msgs; with ROS 2 from PyPI: '
          'build it with build_ros_interfaces.sh and export the PYTHONPATH and LD_LIBRARY_PATH '
          'it prints (README, "Executing through the controller")')


def action_type() -> type:
    """Return control_msgs' FollowJointTrajectory; ValueError with how to get it if it fails."""
    try:
        from control_msgs.action import FollowJointTrajectory
        from rclpy.type_support import check_for_type_support

        check_for_type_support(FollowJointTrajectory)
    except Exception as exc:  # noqa: BLE001 - not installed, or its C libraries do not load
        raise ValueError(f'execution action needs control_msgs, which does not load here '
                         f'({type(exc).__name__}: {str(exc).splitlines()[0]}): '
                         f'{HOW_TO}') from None
    return FollowJointTrajectory


def resolve_action(node: Node, name: str) -> str:
    """
    Return action ``name`` made absolute by ``node``'s namespace and remapping rules.

    The rules of ``--ros-args -r from:=to`` that name no type apply to topics and services
    alike, so the service resolution is the action's. ValueError if the name is not valid.
    """
    try:
        return node.resolve_service_name(name)
    except Exception as exc:  # noqa: BLE001 - rclpy raises its own types for invalid names
        why = str(exc).splitlines()[0].split(', at ')[0] if str(exc) else type(exc).__name__
        raise ValueError(f'{name!r} is not a valid action name: {why}') from None


def start_mismatch(names: Sequence[str], planned: Sequence[float],
                   measured: Mapping[str, float], tolerance: float) -> str | None:
    """
    Return why a plan from ``planned`` may not be sent while joint_states say ``measured``.

    None when every joint is within ``tolerance`` rad (0: not checked).
    """
    if tolerance <= 0:
        return None
    missing = [n for n in names if n not in measured]
    if missing:
        return (f"no joint_states for {', '.join(missing)}: the controller's state is not "
                'known, so the start cannot be checked (start_tolerance 0 sends unchecked)')
    now = [measured[n] for n in names]
    worst = max(range(len(names)), key=lambda j: abs(now[j] - planned[j]))
    gap = abs(now[worst] - planned[worst])
    if gap <= tolerance:
        return None
    return (f'the plan starts {gap:.4g} rad from joint_states on {names[worst]} (start_tolerance '
            f'{tolerance:g} rad): planned from ({", ".join(f"{q:.4f}" for q in planned)}), '
            f'joint_states ({", ".join(f"{q:.4f}" for q in now)}) rad')


def position_error(goal: Mapping[str, float],
                   measured: Mapping[str, float]) -> tuple[float | None, str]:
    """Return the largest |joint_states - goal| (rad) and its joint; (None, '') if not known."""
    if not goal or any(n not in measured for n in goal):
        return None, ''
    name = max(goal, key=lambda n: abs(measured[n] - goal[n]))
    return abs(measured[name] - goal[name]), name


def result_status(goal_status: int, error_code: int, preempted: bool,
                  stopping: bool) -> str:
    """Name the end of an accepted goal from its GoalStatus and its result's error_code."""
    if preempted and (goal_status == GoalStatus.STATUS_CANCELED
                      or goal_status == GoalStatus.STATUS_ABORTED and error_code == 0):
        return 'preempted'                    # cancelled, or aborted for the newer goal
    if goal_status == GoalStatus.STATUS_CANCELED:
        return 'shut_down' if stopping else 'cancelled'
    if goal_status == GoalStatus.STATUS_SUCCEEDED and error_code == 0:
        return 'executed'
    return RESULT_CODES.get(error_code, 'aborted') if error_code else 'aborted'


def describe_end(what: str, error: float | None, joint: str, error_string: str) -> str:
    """Write an execution's end for a person: what happened, where the arm was, and why."""
    where = '' if error is None else f' ({error:.3g} rad from the goal on joint {joint})'
    return what + where + (f'; controller: {error_string}' if error_string else '')


@dataclass
class Motion:
    """One planned motion on its way to the controller."""

    job: Job
    action: str                       # the controller's action, resolved (absolute)
    trajectory: JointTrajectory
    goal: dict[str, float]            # the planned final joint angles, by name
    start: list[float]                # the joint angles it was planned from, in goal's order
    duration: float                   # s
    timeout: float                    # controller_timeout when it was planned, s
    start_tolerance: float            # start_tolerance when it was planned, rad
    deadline: float = math.inf        # monotonic time its current state gives up
    state: str = 'waiting'            # waiting, sent, accepted, settling (its result came)
    handle: Any = None                # the ClientGoalHandle once accepted
    preempted_by: str = ''            # the job whose motion replaces this one
    result: tuple[str, int, str] = ('', 0, '')   # status, error_code, error_string


class ActionExecution:
    """Send planned motions to a FollowJointTrajectory server and report how each ended."""

    def __init__(self, node: Node, report: Callable[[Job, str, str, Execution], None],
                 measured: Callable[[Sequence[str]], Mapping[str, float]]) -> None:
        """
        Create the action client on ``node``.

        ``report(job, status, message, execution)`` publishes an execution status;
        ``measured(names)`` gives the newest joint_states angles.
        """
        self._node = node
        self._action = action_type()
        self._report, self._measured = report, measured
        self._clients: dict[str, ActionClient] = {}         # by resolved action name
        self._handed: collections.deque[Motion] = collections.deque()   # worker -> executor
        self._waiting: Motion | None = None
        self._sent: list[Motion] = []
        self._stopping = False
        self._settled = threading.Event()
        self._take = node.create_guard_condition(self._take_handed)
        self._stop = node.create_guard_condition(self._cancel_all)
        node.create_timer(TICK_S, self._tick)

    # --- any thread ---------------------------------------------------------------------------

    def submit(self, motion: Motion) -> None:
        """Hand a planned motion over: it is sent, preempting the one executing."""
        self._handed.append(motion)
        self._take.trigger()

    def cancel(self, job: Job) -> None:
        """Cancel ``job``'s motion (executor thread): it ends ``preempted``, as by a newer one."""
        for motion in list(self._handed):              # handed over, not yet taken
            if motion.job is job:
                motion.preempted_by = 'a cancel'
        if self._waiting is not None and self._waiting.job is job:
            self._end(self._waiting, 'preempted', 'not sent: cancelled')
            self._waiting = None
        for motion in self._sent:
            if motion.job is job:
                motion.preempted_by = motion.preempted_by or 'a cancel'
                if motion.handle is not None and motion.state == 'accepted':
                    motion.handle.cancel_goal_async()

    def shut_down(self, timeout: float) -> bool:
        """Cancel what is executing; wait up to ``timeout`` s for the cancels. True if done."""
        self._settled.clear()
        self._stop.trigger()
        return self._settled.wait(timeout)

    # --- executor thread ----------------------------------------------------------------------

    def _take_handed(self) -> None:
        while self._handed:
            motion = self._handed.popleft()
            if self._stopping:
                self._end(motion, 'shut_down', 'not sent: shutting down')
                continue
            if motion.preempted_by:                     # cancelled before it was taken
                self._end(motion, 'preempted', 'not sent: cancelled')
                continue
            if self._waiting is not None:
                self._end(self._waiting, 'preempted',
                          f'not sent: {motion.job.label} was planned before it could be')
            motion.deadline = time.monotonic() + motion.timeout
            self._waiting = motion
        self._send_waiting()

    def _send_waiting(self) -> None:
        """
        Send the waiting motion if the server is there, cancelling the ones it preempts.

        Unless its start is off the newest joint_states: then it is refused, and what executes
        goes on. A server whose joint_states have not come yet is waited for as a server is.
        """
        motion = self._waiting
        if motion is None or not self._client(motion.action).server_is_ready():
            return
        names = list(motion.goal)
        measured = self._measured(names)
        if (motion.start_tolerance > 0 and len(measured) < len(names)
                and time.monotonic() <= motion.deadline):
            return                     # the controller's first joint_states are on their way
        self._waiting = None
        problem = start_mismatch(names, motion.start, measured, motion.start_tolerance)
        if problem:
            self._end(motion, 'refused', f'not sent: {problem}')
            return
        for older in self._sent:
            older.preempted_by = older.preempted_by or motion.job.label
            if older.handle is not None and older.state == 'accepted':
                older.handle.cancel_goal_async()
        motion.state, motion.deadline = 'sent', time.monotonic() + motion.timeout
        self._sent.append(motion)
        future = self._client(motion.action).send_goal_async(
            self._action.Goal(trajectory=motion.trajectory))
        future.add_done_callback(functools.partial(self._on_response, motion))

    def _client(self, action: str) -> ActionClient:
        """Return the client of the resolved ``action``, made the first time it is named."""
        if action not in self._clients:
            self._clients[action] = ActionClient(self._node, self._action, action)
        return self._clients[action]

    def _on_response(self, motion: Motion, future: Any) -> None:
        handle = future.result()
        if motion not in self._sent:                  # ended meanwhile (timed out, shut down)
            if handle.accepted:
                handle.cancel_goal_async()
            return
        if not handle.accepted:
            self._end(motion, 'rejected', 'the controller rejected the goal')
            return
        motion.handle, motion.state = handle, 'accepted'
        motion.deadline = time.monotonic() + motion.duration + motion.timeout
        self._report(motion.job, 'accepted', 'the controller accepted the goal', Execution())
        if self._stopping:
            self._cancel_at_shutdown(motion)
        elif motion.preempted_by:
            handle.cancel_goal_async()
        handle.get_result_async().add_done_callback(functools.partial(self._on_result, motion))

    def _on_result(self, motion: Motion, future: Any) -> None:
        """Take the controller's result; the motion ends ``SETTLE_S`` later (``_tick``)."""
        if motion not in self._sent:
            return
        response = future.result()
        code, said = response.result.error_code, response.result.error_string
        status = result_status(response.status, code, bool(motion.preempted_by), self._stopping)
        motion.state, motion.result = 'settling', (status, code, said)
        motion.deadline = time.monotonic() + SETTLE_S

    def _finish(self, motion: Motion) -> None:
        """End a motion with its result."""
        status, code, said = motion.result
        what = {'executed': 'reached the goal', 'shut_down': 'cancelled at shutdown',
                'preempted': f'cancelled for {motion.preempted_by}'}.get(
                    status, status.replace('_', ' '))
        self._end_where(motion, status, what, code, said)

    def _end_where(self, motion: Motion, status: str, what: str, code: int | None = None,
                   said: str = '') -> None:
        """End a sent motion, saying where joint_states put the arm against its goal."""
        error, joint = position_error(motion.goal, self._measured(list(motion.goal)))
        self._end(motion, status, describe_end(what, error, joint, said),
                  Execution(code, said, error, joint))

    def _tick(self) -> None:
        """Send a motion whose server has appeared; end the ones past their deadline."""
        self._send_waiting()
        now = time.monotonic()
        motion = self._waiting
        if motion is not None and now > motion.deadline:
            self._waiting = None
            self._end(motion, 'no_controller', f'no FollowJointTrajectory server on '
                      f'{motion.action} within {motion.timeout:g} s (set controller_action '
                      "to the controller's action, e.g. /arm_controller/follow_joint_trajectory)")
        for motion in [m for m in self._sent if now > m.deadline]:
            if motion.state == 'settling':
                self._finish(motion)
                continue
            if motion.state == 'sent':
                reason = f'the controller did not answer the goal within {motion.timeout:g} s'
            else:
                motion.handle.cancel_goal_async()
                reason = (f'the controller had not finished {motion.timeout:g} s after the '
                          f"motion's {motion.duration:.3f} s; cancelled")
            self._end_where(motion, 'timed_out', reason)

    def _cancel_all(self) -> None:
        """
        At shutdown: end the waiting motion, cancel the executing ones.

        Each ends when the controller has answered its cancel (then the request reached it),
        one with its result in hand at once; a goal still unanswered is cancelled when accepted.
        """
        self._stopping = True
        if self._waiting is not None:
            self._end(self._waiting, 'shut_down', 'not sent: shutting down')
            self._waiting = None
        for motion in list(self._sent):
            if motion.state == 'accepted':
                self._cancel_at_shutdown(motion)
            elif motion.state == 'settling':
                self._finish(motion)
        self._settle()

    def _cancel_at_shutdown(self, motion: Motion) -> None:
        future = motion.handle.cancel_goal_async()
        future.add_done_callback(functools.partial(self._on_cancelled, motion))

    def _on_cancelled(self, motion: Motion, future: Any) -> None:
        """End a motion cancelled at shutdown once the controller has answered the cancel."""
        if motion in self._sent:
            self._end_where(motion, 'shut_down', 'cancelled at shutdown')

    def _end(self, motion: Motion, status: str, message: str,
             execution: Execution | None = None) -> None:
        if motion in self._sent:
            self._sent.remove(motion)
        self._report(motion.job, status, message, execution or Execution())
        self._settle()

    def _settle(self) -> None:
        """At shutdown, say so once nothing sent is left."""
        if self._stopping and not self._sent:
            self._settled.set()
