# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The ROS 2 planner node ``trajplan`` (executable ``planner_node``): a thin shell around ``plan``.

Interfaces (all names relative, so namespaces and ``--ros-args -r`` remapping apply):

* ``goal`` (geometry_msgs/msg/Point, m, arm base frame): plan each goal and, on success,
  publish the trajectory. While the node is busy only the newest goal waits; older waiting
  goals are dropped with a log line naming them.
* ``plan_trajectory`` (nav_msgs/srv/GetPlan): plan ``request.goal.pose.position`` (tolerance
  in m when above zero; ``request.start`` is ignored). The response's plan is the tool path of
  the trajectory, one pose per trajectory point (empty on failure); success also publishes.
* ``joint_trajectory`` (trajectory_msgs/msg/JointTrajectory, out): the form
  joint_trajectory_controller accepts (header.stamp zero = start now).
* ``joint_states`` (sensor_msgs/msg/JointState, in): the start state, matched by joint name.
  Without it the start is the end of the last published trajectory, else ``start_positions``.

Planning runs on one daemon worker thread, so the executor keeps answering parameter
services, goals and other service calls meanwhile, and Ctrl-C or SIGTERM ends the process
promptly even mid-plan. A service call is answered first; the trajectory is published and the
plan logged (with its start, result and ``plan_time_s``) just after.
"""
from __future__ import annotations

import itertools
import math
import sys
import threading
from typing import Any, Sequence

from geometry_msgs.msg import Point, PoseStamped
from nav_msgs.msg import Path
from nav_msgs.srv import GetPlan
import numpy as np
from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
import rclpy
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.logging import get_logger
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory
from trajplan_ros.planning import plan
from trajplan_ros.ros.mailbox import Job, Mailbox
from trajplan_ros.ros.messages import path_msg, trajectory_msg
from trajplan_ros.ros.settings import PARAMETERS, ParameterSpec, Settings


__all__ = ['PlannerNode', 'main']

#: Executor threads. Each service call waiting for its plan holds one, so up to this many
#: minus one calls can wait while parameter services, goals and joint states still get answered;
#: beyond that, calls queue in the executor (none is dropped).
EXECUTOR_THREADS = 8

#: After answering a service call, how long the worker may wait (for nothing but the answer to
#: go out) before it publishes the trajectory and logs, unless new work arrives first.
ANSWER_GRACE_S = 5e-3
#: PoseStamped messages the worker makes ahead while idle, for the next service answer's path.
BLANK_POSES = 200
#: Python's GIL switch interval in the node process (default 5 ms): how long an executor thread
#: may wait for the GIL while the worker computes. Shorter keeps answers prompt during plans.
SWITCH_INTERVAL_S = 5e-4


def _fmt(xyz: Sequence[float]) -> str:
    return '(' + ', '.join(f'{v:.6g}' for v in xyz) + ')'


def _descriptor(spec: ParameterSpec) -> ParameterDescriptor:
    """Build the descriptor of a parameter: its description and its range or choices."""
    descriptor = ParameterDescriptor(description=spec.description)
    if spec.choices:
        descriptor.additional_constraints = 'one of: ' + ', '.join(spec.choices)
    if spec.bounds is not None and isinstance(spec.default, int):
        low, high = spec.bounds
        descriptor.integer_range = [IntegerRange(from_value=low, to_value=high, step=1)]
    elif spec.bounds is not None:
        low, high = spec.bounds
        descriptor.floating_point_range = [FloatingPointRange(from_value=low, to_value=high,
                                                              step=0.0)]
    return descriptor


class PlannerNode(Node):
    """Node ``trajplan``: goals and GetPlan calls in, JointTrajectory out."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('trajplan', **kwargs)
        self._parameter_names: list[str] = []
        self._declare_parameters()
        self._settings = Settings.from_parameters(self._parameter_values())
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

        self._state_lock = threading.Lock()
        self._measured: dict[str, float] = {}     # from joint_states
        self._last_end: dict[str, float] = {}     # end of the last published trajectory
        self._goal_ids = itertools.count(1)
        self._call_ids = itertools.count(1)
        self._mailbox = Mailbox()
        self._blanks: list[PoseStamped] = []     # worker thread only

        self._publisher = self.create_publisher(JointTrajectory, 'joint_trajectory', 10)
        # a deep queue: every goal must reach _on_goal to be planned or logged as dropped
        self.create_subscription(Point, 'goal', self._on_goal, 100)
        # best effort: matches joint_states publishers of either reliability
        self.create_subscription(JointState, 'joint_states', self._on_joint_states,
                                 qos_profile_sensor_data)
        self.create_service(GetPlan, 'plan_trajectory', self._on_plan_call,
                            callback_group=ReentrantCallbackGroup())
        self._worker = threading.Thread(target=self._work, name='trajplan_worker', daemon=True)
        self._worker.start()
        arm = self._settings.arm
        self.get_logger().info(
            f"ready: {arm.n_joints}-joint arm ({', '.join(arm.joint_names)}), "
            f'{self._settings.algorithm}, {self._settings.omega} rad/s')

    # --- parameters -------------------------------------------------------------------------

    def _declare_parameters(self) -> None:
        for spec in PARAMETERS:
            self.declare_parameter(spec.name, spec.default, _descriptor(spec))
            self._parameter_names.append(spec.name)

    def _parameter_values(self) -> dict[str, Any]:
        return {p.name: p.value for p in self.get_parameters(self._parameter_names)}

    def _check_parameters(self, params: list[Parameter]) -> SetParametersResult:
        values = self._parameter_values()
        values.update({p.name: p.value for p in params})
        try:
            Settings.from_parameters(values)
        except ValueError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, params: list[Parameter]) -> None:
        self._settings = Settings.from_parameters(self._parameter_values())
        self.get_logger().info('parameters set for the next plan: ' +
                               ', '.join(f'{p.name}={p.value}' for p in params))

    # --- inputs -----------------------------------------------------------------------------

    def _on_goal(self, msg: Point) -> None:
        job = Job(f'goal #{next(self._goal_ids)}', (msg.x, msg.y, msg.z))
        dropped = self._mailbox.put_goal(job)
        if dropped is not None:
            self.get_logger().info(f'dropped {dropped.label} {_fmt(dropped.goal)} m: '
                                   f'superseded by {job.label} while planning')

    def _on_joint_states(self, msg: JointState) -> None:
        if not msg.position:
            return
        if len(msg.position) != len(msg.name):
            self.get_logger().warning(
                f'ignored joint_states: {len(msg.name)} names but {len(msg.position)} positions',
                throttle_duration_sec=5.0)
            return
        ours = set(self._settings.arm.joint_names)
        update = {n: float(q) for n, q in zip(msg.name, msg.position) if n in ours}
        bad = [n for n, q in update.items() if not math.isfinite(q)]
        if bad:
            self.get_logger().warning(
                f"ignored joint_states: non-finite position for {', '.join(bad)}",
                throttle_duration_sec=5.0)
            return
        with self._state_lock:
            self._measured.update(update)

    def _on_plan_call(self, request: GetPlan.Request,
                      response: GetPlan.Response) -> GetPlan.Response:
        p = request.goal.pose.position
        job = Job(f'service call #{next(self._call_ids)}', (p.x, p.y, p.z),
                  tolerance=request.tolerance if request.tolerance > 0 else None,
                  done=threading.Event(), answered=threading.Event())
        if self._mailbox.put_call(job):
            job.done.wait()
        response.plan = job.path if job.path is not None else Path(
            header=self._header(self._settings.base_frame))
        job.answered.set()
        return response

    # --- planning (worker thread) -----------------------------------------------------------

    def _header(self, frame_id: str) -> Header:
        return Header(stamp=self.get_clock().now().to_msg(), frame_id=frame_id)

    def _start(self, settings: Settings) -> np.ndarray:
        """Return, per joint, joint_states, else the last trajectory's end, else the parameter."""
        with self._state_lock:
            known = {**self._last_end, **self._measured}
        names = settings.arm.joint_names
        return np.array([known.get(n, q) for n, q in zip(names, settings.start)])

    def _work(self) -> None:
        while True:
            # make the next answer's poses while idle (a service answer waits on their making)
            self._blanks.extend(PoseStamped() for _ in range(BLANK_POSES - len(self._blanks)))
            if (job := self._mailbox.take()) is None:
                return
            try:
                self._plan(job)
            except Exception as exc:  # noqa: BLE001 - a core bug must not end the planning thread
                self.get_logger().error(
                    f'{job.label} {_fmt(job.goal)} m: planning failed: {exc!r}')
            finally:
                self._answer(job)

    @staticmethod
    def _answer(job: Job, path: Path | None = None) -> None:
        """
        Hand a service call its path (None: an empty plan) once.

        Then wait until the service callback has taken it, so the answer goes out before this
        thread carries on.
        """
        if job.done is not None and not job.done.is_set():
            job.path = path
            job.done.set()
            job.answered.wait(timeout=1.0)

    def _plan(self, job: Job) -> None:
        """Plan one job; on success answer the call (if any) with the tool path, then publish."""
        s = self._settings
        start = self._start(s)
        where = f'{job.label} {_fmt(job.goal)} m from q = {_fmt(start)} rad'
        self.get_logger().debug(f'planning {where}')
        result = plan(job.goal, start, arm=s.arm, mode=s.mode, algorithm=s.algorithm,
                      omega=s.omega, tolerance=job.tolerance or s.tolerance, seed=s.seed,
                      population=s.population, max_iter=s.max_iter)
        took = f'planned in {1e3 * result.plan_time_s:.3f} ms'
        if not result.success:
            self._answer(job)
            optimised = f'; {took}' if result.joint_goal is not None else ''
            self.get_logger().warning(
                f'{where}: {result.status.value}: {result.message}{optimised}')
            return
        traj = result.trajectory(s.arm, s.sample_period)
        if job.done is not None:
            self._answer(job, path_msg(s.arm, traj, self._header(s.base_frame), self._blanks))
            # the executor thread still has to send the answer; publishing now would compete
            # with it for the interpreter lock, so give it a moment unless more work is waiting
            self._mailbox.wait_for_work(ANSWER_GRACE_S)
        if self._mailbox.closed:
            return
        self._publisher.publish(trajectory_msg(traj))
        with self._state_lock:
            self._last_end = dict(zip(traj.joint_names, traj.positions[-1].tolist()))
        self.get_logger().info(f'{where}: {result.message}; {took}; published {len(traj.times)} '
                               f'points over {traj.duration:.3f} s')

    def destroy_node(self) -> None:
        """
        Answer the service calls still waiting with an empty plan, then destroy the node.

        A plan in progress cannot be interrupted: the daemon worker thread ends with the process.
        """
        waiting = self._mailbox.close()
        for job in waiting:
            if self.context.ok():     # after Ctrl-C or SIGTERM, /rosout is gone already
                self.get_logger().info(f'shutting down: {job.label} {_fmt(job.goal)} m unplanned')
            job.done.set()
        for job in waiting:           # let the executor threads send those answers first
            job.answered.wait(timeout=1.0)
        super().destroy_node()


def main(args: list[str] | None = None) -> int:
    """Run the node until Ctrl-C or SIGTERM (rclpy handles both)."""
    sys.setswitchinterval(SWITCH_INTERVAL_S)
    rclpy.init(args=args)
    try:
        node = PlannerNode()
    except (ValueError, ParameterException) as exc:
        get_logger('trajplan').fatal(f'invalid parameters: {exc}')
        rclpy.try_shutdown()
        return 2
    executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS)
    executor.add_node(node)
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except RuntimeError:
        # the signal handler may shut the context down while the executor builds its wait
        # set (ros2/rclpy#398): that is the shutdown we asked for; anything else is not
        if rclpy.ok():
            raise
    finally:
        node.destroy_node()
        executor.shutdown()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
