# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
What became of each goal and call, as diagnostic_msgs/DiagnosticStatus on ``plan_results``.

GetPlan has no field for a reason and a topic goal has no answer, so the node publishes one
status per goal and per call when it ends: planned, refused, not reached, timed out,
superseded or unplanned at shutdown. A caller finds its own by what it sent: a call or a
stamped goal (PoseStamped, PointStamped) by its ``header.stamp`` (the client's send time,
which makes it unique; it is also when the goal's frame is posed through tf), a Point goal by
its point among the outcomes that arrive after it sent it (the ones before are a late
joiner's history). The status's ``message`` is the reason, as the node logs it.

Fields: ``level`` OK (planned), WARN (superseded, or unplanned at shutdown) or ERROR (every
other end); ``name`` the node and the job (``/trajplan: service call #3``); ``values``:
``request`` (``service call`` or ``goal``), ``stamp`` (a call's or a stamped goal's
``sec.nanosec``, else empty), ``x``, ``y``, ``z`` (the goal, m, exact decimal round trip; in
the base frame once its frame is posed), ``status`` (``succeeded``,
``rejected``, ``not_reached``, ``timed_out``, ``cancelled``, ``refused``, ``superseded``,
``shut_down`` or ``failed``), ``stage`` (``plan``), ``motion_time_s`` and ``via_points``
(how many via points the motion rests at: 0 for a direct motion; both empty unless planned),
and with the collision check on, ``clearance_m`` and ``clearance_pair``: the motion's least
clearance (m) and where it occurs (empty otherwise).

With ``execution: action`` a planned motion that is sent to the controller gets more statuses
of the same name, ``stage`` ``execution`` (``ros.execution``): ``accepted`` (OK), then one end:
``executed`` (OK), ``preempted`` or ``shut_down`` (WARN), or ERROR: ``rejected`` (by the
controller), ``refused`` (not sent: the start differs from joint_states), ``no_controller``,
``timed_out``, ``cancelled`` (by another client), ``invalid_goal``, ``invalid_joints``,
``old_header_timestamp``, ``path_tolerance_violated``, ``goal_tolerance_violated`` or ``aborted``
(the controller's result code). Their ``error_code`` and ``error_string`` are the controller's
result, ``position_error_rad`` and ``position_error_joint`` the largest difference between the
last joint_states and the planned goal and its joint (empty where not known).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy


__all__ = ['Execution', 'QOS', 'TOPIC', 'TERMINAL', 'describe_stamp', 'outcome_status',
           'outcome_values']

#: The topic the node publishes every outcome on (relative: it follows the node's namespace).
TOPIC = 'plan_results'
#: Reliable, and the last 100 kept for a subscriber that matches late (transient local): a
#: caller's request can reach the node before the node has matched the caller's subscription.
QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                 durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: Statuses that are not the caller's goal's fault: WARN, not ERROR.
_WARNINGS = ('superseded', 'shut_down', 'preempted')
#: Statuses that are not failures: OK.
_SUCCESSES = ('succeeded', 'accepted', 'executed')
#: Every execution status but ``accepted`` ends the execution of its motion.
TERMINAL = ('executed', 'preempted', 'shut_down', 'rejected', 'refused', 'no_controller',
            'timed_out', 'cancelled', 'invalid_goal', 'invalid_joints', 'old_header_timestamp',
            'path_tolerance_violated', 'goal_tolerance_violated', 'aborted')


@dataclass(frozen=True)
class Execution:
    """The values of an execution status: the controller's result and where the arm stopped."""

    error_code: int | None = None             # FollowJointTrajectory's Result.error_code
    error_string: str = ''
    position_error_rad: float | None = None   # largest |joint_states - planned goal|
    position_error_joint: str = ''            # and its joint


def describe_stamp(stamp: tuple[int, int] | None) -> str:
    """Write a header stamp (sec, nanosec) as ``sec.nanosec``, or '' for none."""
    return '' if stamp is None else f'{stamp[0]}.{stamp[1]:09d}'


def outcome_status(name: str, request: str, stamp: tuple[int, int] | None,
                   goal: Sequence[float], status: str, message: str,
                   motion_time_s: float | None = None,
                   clearance: tuple[float, str] | None = None,
                   via_points: int | None = None,
                   execution: Execution | None = None) -> DiagnosticStatus:
    """
    Build the DiagnosticStatus of one goal's or call's end (see the module docstring).

    With ``execution``, the status of its motion's execution (stage ``execution``).
    """
    done = execution or Execution()
    if status in _SUCCESSES:
        level = DiagnosticStatus.OK
    else:
        level = DiagnosticStatus.WARN if status in _WARNINGS else DiagnosticStatus.ERROR
    values = {'request': request, 'stamp': describe_stamp(stamp),
              **{axis: repr(float(v)) for axis, v in zip('xyz', goal)},
              'status': status, 'stage': 'plan' if execution is None else 'execution',
              'motion_time_s': '' if motion_time_s is None else repr(float(motion_time_s)),
              'via_points': '' if via_points is None else str(via_points),
              'clearance_m': '' if clearance is None else repr(float(clearance[0])),
              'clearance_pair': '' if clearance is None else clearance[1],
              'error_code': '' if done.error_code is None else str(done.error_code),
              'error_string': done.error_string,
              'position_error_rad': ('' if done.position_error_rad is None
                                     else repr(float(done.position_error_rad))),
              'position_error_joint': done.position_error_joint}
    return DiagnosticStatus(level=level, name=name, message=message, hardware_id='',
                            values=[KeyValue(key=k, value=v) for k, v in values.items()])


def outcome_values(msg: DiagnosticStatus) -> dict[str, str]:
    """Return an outcome's values as a dict (key -> text)."""
    return {kv.key: kv.value for kv in msg.values}
