# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
A FollowJointTrajectory server to try execution with (executable ``demo_controller``).

It stands in for joint_trajectory_controller and joint_state_broadcaster: it serves
``follow_joint_trajectory`` (a relative name; remapping applies) and publishes
``joint_states`` at ``rate`` Hz. An accepted goal's trajectory is followed in time, by linear
interpolation between its points, from where the joints are when it is accepted
(``header.stamp`` zero: start now). One goal executes at a time:
a new goal preempts the one executing (aborted), a cancel request stops the arm where it is.
A goal naming a joint it does not have is rejected, as joint_trajectory_controller does.
Its parameters ``fail``, ``fail_after`` and ``goal_error`` may change while it runs (each goal
takes them as they are when it is accepted).

``fail`` makes it fail as a real controller can, with the result codes of
control_msgs/action/FollowJointTrajectory: ``reject`` (the goal is rejected), ``invalid_goal``,
``invalid_joints``, ``old_header_timestamp`` (accepted, then aborted with that code),
``path_tolerance`` (aborted ``fail_after`` s into the motion, the arm stopping there),
``goal_tolerance`` (the last joint ends ``goal_error`` rad off its goal, aborted) or ``stall``
(accepted, never moves nor answers). Needs control_msgs, as the node's ``execution: action``.
"""
from __future__ import annotations

from dataclasses import dataclass
import sys
import time
from typing import Any

import numpy as np
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
import rclpy
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.task import Future
from sensor_msgs.msg import JointState
from trajplan_ros.kinematics import paper_arm
from trajplan_ros.ros.execution import action_type, resolve_action


__all__ = ['DemoController', 'FAILURES', 'main']

#: What ``fail`` accepts: '' (follow every goal) or the failure to show.
FAILURES = ('', 'reject', 'invalid_goal', 'invalid_joints', 'old_header_timestamp',
            'path_tolerance', 'goal_tolerance', 'stall')
#: The result code and error_string each failure ends a goal with.
_ABORTS = {'invalid_goal': (-1, 'the goal is invalid'),
           'invalid_joints': (-2, "the goal's joints do not match the controller's"),
           'old_header_timestamp': (-3, "the goal's header.stamp is in the past"),
           'path_tolerance': (-4, 'Aborted due to path tolerance violation'),
           'goal_tolerance': (-5, 'Aborted due to goal tolerance violation')}


@dataclass
class _Following:
    """The goal being executed: its handle, its path in time, and the future its end sets."""

    handle: Any
    joints: np.ndarray                 # indices of the goal's joints in the controller's
    times: np.ndarray                  # s, from acceptance; 0 is where the joints were
    positions: np.ndarray              # (len(times), len(joints))
    started: float
    done: Future
    fail: str                          # the controller's fail, fail_after and goal_error
    fail_after: float                  # when the goal was accepted
    goal_error: float


class DemoController(Node):
    """Node ``demo_controller``: follow FollowJointTrajectory goals in time, publish the state."""

    def __init__(self) -> None:
        super().__init__('demo_controller')
        arm = paper_arm()
        p = {
            'joints': (list(arm.joint_names), 'joint names it controls'),
            'positions': ([0.0] * arm.n_joints, 'joint angles at start-up, rad'),
            'rate': (50.0, 'joint_states rate and control rate, Hz'),
            'fail': ('', 'how to fail every goal: ' + ', '.join(f for f in FAILURES if f)
                     + "; '': follow it"),
            'fail_after': (0.5, 'fail path_tolerance: when, s into the motion'),
            'goal_error': (0.03, 'fail goal_tolerance: how far the last joint ends off, rad'),
        }
        for name, (default, text) in p.items():
            self.declare_parameter(name, default, ParameterDescriptor(description=text))
        value = {name: self.get_parameter(name).value for name in p}
        problem = _fail_problem(value['fail'])
        if problem:
            raise ValueError(problem)
        self.add_on_set_parameters_callback(self._check)
        self._names = list(value['joints'])
        if len(value['positions']) != len(self._names):
            raise ValueError(f"positions has {len(value['positions'])} angles for "
                             f'{len(self._names)} joints')
        self._q = np.array(value['positions'], dtype=float)
        self._action = action_type()
        self._active: _Following | None = None
        self._following: dict[int, _Following] = {}     # accepted, by handle, until executed
        self._states = self.create_publisher(JointState, 'joint_states', 10)
        self._name = resolve_action(self, 'follow_joint_trajectory')    # remapping applies
        self._server = ActionServer(self, self._action, self._name, self._execute,
                                    goal_callback=self._on_goal,
                                    handle_accepted_callback=self._on_accepted,
                                    cancel_callback=lambda _: CancelResponse.ACCEPT)
        self.create_timer(1.0 / value['rate'], self._tick)
        self.get_logger().info(f"ready: {self._name}, joints {', '.join(self._names)}")

    def _check(self, params: list[Parameter]) -> SetParametersResult:
        """Refuse a ``fail`` it does not know (the others are read at each goal)."""
        problem = next(filter(None, (_fail_problem(p.value) for p in params
                                     if p.name == 'fail')), None)
        return SetParametersResult(successful=problem is None, reason=problem or '')

    def _setting(self, name: str) -> Any:
        return self.get_parameter(name).value

    def _on_goal(self, goal: Any) -> GoalResponse:
        unknown = sorted(set(goal.trajectory.joint_names) - set(self._names))
        if self._setting('fail') == 'reject' or unknown or not goal.trajectory.points:
            why = (f"unknown joints {', '.join(unknown)}" if unknown else
                   'no points' if not goal.trajectory.points else 'fail reject')
            self.get_logger().info(f'goal rejected: {why}')
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def _on_accepted(self, handle: Any) -> None:
        """End the goal executing (preempted), then execute the new one: one at a time."""
        if self._active is not None:
            self._end(self._active, 'abort', 0, 'preempted by a new goal')
        traj = handle.request.trajectory
        joints = np.array([self._names.index(n) for n in traj.joint_names])
        times = [0.0] + [p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec
                         for p in traj.points]
        positions = [self._q[joints]] + [np.array(p.positions) for p in traj.points]
        self._active = _Following(handle, joints, np.array(times), np.array(positions),
                                  time.monotonic(), Future(), self._setting('fail'),
                                  self._setting('fail_after'), self._setting('goal_error'))
        self._following[id(handle)] = self._active
        self.get_logger().info(f'goal accepted: {len(traj.points)} points over '
                               f'{times[-1]:.3f} s')
        handle.execute()

    async def _execute(self, handle: Any) -> Any:
        """Return the goal's result when the control loop (or a newer goal) ends it."""
        return await self._following.pop(id(handle)).done

    def _tick(self) -> None:
        """Move the executing goal's joints to where its trajectory is now; publish the state."""
        a = self._active
        if a is not None and a.handle.is_cancel_requested:
            self._end(a, 'canceled', 0, 'cancelled on request')
        elif a is not None and a.fail != 'stall':
            t = time.monotonic() - a.started
            if a.fail in ('invalid_goal', 'invalid_joints', 'old_header_timestamp'):
                self._end(a, 'abort', *_ABORTS[a.fail])
            elif a.fail == 'path_tolerance' and t >= a.fail_after:
                self._end(a, 'abort', *_ABORTS['path_tolerance'])
            else:
                self._q[a.joints] = [np.interp(t, a.times, a.positions[:, j])
                                     for j in range(len(a.joints))]
                if t >= a.times[-1]:
                    if a.fail == 'goal_tolerance':
                        self._q[a.joints[-1]] += a.goal_error
                        self._end(a, 'abort', *_ABORTS['goal_tolerance'])
                    else:
                        self._end(a, 'succeed', 0, '')
        msg = JointState(name=self._names, position=self._q.tolist())
        msg.header.stamp = self.get_clock().now().to_msg()
        self._states.publish(msg)

    def _end(self, following: _Following, how: str, code: int, error_string: str) -> None:
        """End a goal (succeed, abort or canceled) with its result; the arm holds where it is."""
        getattr(following.handle, how)()
        if self._active is following:
            self._active = None
        self.get_logger().info(f'goal ended: {how}, error_code {code}'
                               + (f': {error_string}' if error_string else ''))
        following.done.set_result(self._action.Result(error_code=code,
                                                      error_string=error_string))


def _fail_problem(fail: str) -> str | None:
    """Return why ``fail`` is refused, or None."""
    if fail in FAILURES:
        return None
    return f"fail must be one of {', '.join(map(repr, FAILURES))}, got {fail!r}"


def main(args: list[str] | None = None) -> int:
    """Run the controller until Ctrl-C."""
    rclpy.init(args=args)
    try:
        node = DemoController()
    except ValueError as exc:
        print(f'demo_controller: {exc}', file=sys.stderr)
        rclpy.try_shutdown()
        return 2
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
