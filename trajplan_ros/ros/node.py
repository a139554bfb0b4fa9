# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The ROS 2 planner node ``trajplan`` (executable ``planner_node``): a thin shell around ``plan``.

Interfaces (all names relative, so namespaces and ``--ros-args -r`` remapping apply):

* ``goal`` (geometry_msgs/msg/Point, m, arm base frame): plan each goal and, on success,
  publish the trajectory. While the node is busy only the newest goal waits; an older waiting
  goal is logged as superseded.
* ``goal_pose`` (geometry_msgs/msg/PoseStamped; RViz's Goal Pose tool): a goal like ``goal``;
  with ``goal_orientation: approach`` the tool axis points along its orientation's z axis,
  with ``goal_orientation: pose`` the tool frame takes its whole orientation.
* ``plan_trajectory`` (nav_msgs/srv/GetPlan): plan ``request.goal.pose`` (its orientation as
  for ``goal_pose``). The response's plan is the tool path of the trajectory, one pose per
  point (empty on failure).
* ``compute_plan`` (nav_msgs/srv/GetPlan): answered as ``plan_trajectory``, never published.
* With ``moveit_interfaces``: move_group's ``plan_kinematic_path``, ``execute_trajectory``,
  ``move_action`` and ``trajectory_execution_event`` for MoveIt's clients
  (``ros.move_group``): its plans are the node's calls, its executions go through the same
  ``ActionExecution``.
* Frames (``ros.transforms``): a stamped goal (``goal_pose``, ``clicked_point``, the
  services, MoveIt's constraints) is brought into ``base_frame`` through tf where tf2 loads
  (a Buffer fed by ``/tf`` and ``/tf_static``): at its stamp (zero: the newest), the worker
  waiting up to ``transform_timeout`` for it, else refused with tf's reason. A link of the
  robot's URDF that tf does not know is posed by the robot's own forward kinematics at the
  start of the plan. Obstacles (markers, MoveIt's objects) are posed as their frame is when
  they arrive. Without tf2, other frames are refused, naming the URDF's.
* ``joint_trajectory`` (out; with ``execution: topic``), ``planned_path`` (nav_msgs/msg/Path,
  out, for RViz), ``/diagnostics`` (diagnostic_msgs/msg/DiagnosticArray, out, 1 Hz).
* ``plan_results`` (diagnostic_msgs/msg/DiagnosticStatus, out): how each goal and call ended
  and why, with what the caller sent (``ros.outcomes``).
* ``follow_joint_trajectory`` (control_msgs/action/FollowJointTrajectory, client; with
  ``execution: action``; the parameter ``controller_action`` names another): each motion is
  sent as a goal there instead, and how the controller ends it goes to ``plan_results``
  (``ros.execution``); ``execution: none`` sends nothing.
* ``joint_states`` (sensor_msgs/msg/JointState, in): the start state, matched by joint name.
* ``clicked_point`` (geometry_msgs/msg/PointStamped, in; RViz's Publish Point tool): a goal.
* ``robot_description`` (std_msgs/msg/String, in; reliable, transient local, depth 1, as
  robot_state_publisher offers it): a URDF; unless the ``robot_description`` parameter is set,
  the arm is built from it for the next plan. A refused description is logged and the arm in
  use is kept (``ros.settings`` says which settings a description overrides).

Concurrency, all of it:

* One executor thread (a SingleThreadedExecutor) runs every callback. None of them blocks:
  the service callback is a coroutine that queues its call and ``await``s the call's Future.
* One worker thread takes jobs from the ``Mailbox`` (calls in arrival order, then the newest
  goal), poses each goal's frame (waiting for tf up to ``transform_timeout``, in slices that a
  shutdown ends), plans them, publishes, and hands each call's answer back through a deque and
  the guard condition ``_deliver``; the guard's callback completes the Futures on the executor
  thread. No Future is ever completed from another thread: rclpy 7.1.6 (PyPI) does not wake
  the executor for that, later Jazzy releases do; this path works with both.
* The main thread waits for SIGINT or SIGTERM (rclpy's own signal handling is off), then
  ``shut_down`` stops intake, stops the running plan, answers every waiting call with an empty
  plan; the worker, then the executor thread, are joined, and only then the context is shut
  down. A thread still running ``EXIT_WAIT_S`` later (a first start's compile) is left to end
  with the process: the interpreter's exit would unwind it inside C++ and abort.
* With ``execution: action``, the worker hands each planned motion to ``ActionExecution``
  (a deque and a guard condition); its action client, futures and timer run on the executor
  thread, and ``shut_down`` cancels the executing goal through it before the context ends.
* Each job's outcome goes to ``plan_results`` from whichever of the three threads ends it (a
  refusal or a superseded goal on the executor, a plan on the worker, shutdown on the main
  thread); ``Job.reported``, set under the answer lock, lets only the first through.
* Nothing may hold the interpreter lock for long: after the warm-up the worker freezes what
  exists (``gc.freeze``), so no full garbage collection walks the modules and kernels (0.1 to
  1.5 s under load); the lines logged for every goal and call go through ``QuickLogger``.

QoS: the service and the goal subscription keep all samples (reliable, KEEP_ALL), so no
request or goal that reached the node's reader is overwritten before a callback sees it; the
queue of calls is bounded by ``max_queued_calls`` instead. joint_states are taken best effort
(matches publishers of either reliability; only the newest state matters). ``plan_results``
keeps its last 100 outcomes for subscribers that match late (transient local).
"""
from __future__ import annotations

import collections
import gc
import itertools
import math
import os
import signal
import sys
import threading
import time
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Point, PointStamped, Pose, PoseStamped
from nav_msgs.msg import Path
from nav_msgs.srv import GetPlan
import numpy as np
from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
import rclpy
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.logging import get_logger
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, qos_profile_sensor_data, QoSProfile,
                       ReliabilityPolicy)
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future
from sensor_msgs.msg import JointState
from std_msgs.msg import Header, String
from trajectory_msgs.msg import JointTrajectory
from trajplan_ros.collision.distances import CollisionWorld
from trajplan_ros.collision.scene import Obstacle, Scene
from trajplan_ros.planning import Mode, prepare
from trajplan_ros.planning.planner import describe_goal
from trajplan_ros.ros import job as jobs, outcomes
from trajplan_ros.ros.diagnostics import Counters, diagnostic_array
from trajplan_ros.ros.execution import action_type, ActionExecution, Motion, resolve_action
from trajplan_ros.ros.joint_states import JointStateMonitor
from trajplan_ros.ros.mailbox import Admission, Job, Mailbox
from trajplan_ros.ros.messages import path_msg, trajectory_msg
from trajplan_ros.ros.move_group import MoveGroupServer, NodeHooks
from trajplan_ros.ros.quick_log import QuickLogger
from trajplan_ros.ros.scene_topics import LiveScene, world_markers
from trajplan_ros.ros.settings import PARAMETERS, ParameterSpec, Settings
from trajplan_ros.ros.transforms import (arrival_note, frame_pose, frame_problem, listen,
                                         Transforms)
from visualization_msgs.msg import MarkerArray


__all__ = ['PlannerNode', 'main']

#: Every request and goal that reached the node's reader is kept until a callback takes it.
KEEP_ALL = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE)
#: robot_state_publisher's robot_description: the latest description, also to late joiners.
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: After handing over a call's answer, how long the worker may wait (for nothing but the answer
#: to go out) before it publishes the trajectory and logs, unless new work arrives first.
ANSWER_GRACE_S = 5e-3
#: Python's GIL switch interval in the node process (default 5 ms): how long the executor
#: thread may wait for the GIL while the worker computes.
SWITCH_INTERVAL_S = 5e-4
#: At shutdown: how long to wait for the running plan to stop and for the answers to go out.
SHUTDOWN_STEP_S = 0.5
#: At exit: how long to wait for each thread to end (a plan stops at its next check).
EXIT_WAIT_S = 5.0


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


def request_problem(request: GetPlan.Request, settings: Settings,
                    tf: Transforms | None = None) -> str | None:
    """Return why a GetPlan request is refused before planning, or None."""
    tolerance = request.tolerance
    if not math.isfinite(tolerance) or tolerance < 0:
        return (f'tolerance {tolerance} m is not allowed: give 0 (use the tolerance parameter) '
                'or a positive finite value')
    return goal_problem(request.goal.header.frame_id, _quaternion(request.goal.pose), settings,
                        tf)


def _as_planned(job: Job, settings: Settings) -> Settings:
    """Return the settings ``job`` plans with: its own changes, and its goal's kind."""
    goal = job.goal
    mode = Mode.POSE if goal.joint_goal is not None else goal.mode    # a joint goal: every joint
    changes = dict(job.request_changes)
    if mode is not settings.request.goal.mode:
        changes['goal'] = settings.request.goal.replace(mode=mode)
    return settings.planning_with(**changes) if changes else settings


def goal_problem(frame: str, orientation: tuple[float, ...] | None, settings: Settings,
                 tf: Transforms | None = None) -> str | None:
    """Return why a goal in ``frame`` (a pose's ``orientation``) cannot be planned, or None."""
    problem = frame_problem(frame, settings, tf is not None)
    if problem is None and settings.goal_orientation != 'ignore' and orientation is not None:
        problem = jobs.rotation_problem(orientation)
    return problem


def _quaternion(pose: Pose) -> tuple[float, float, float, float]:
    """Return a pose's orientation as (x, y, z, w)."""
    o = pose.orientation
    return (o.x, o.y, o.z, o.w)


class PlannerNode(Node):
    """Node ``trajplan``: goals and GetPlan calls in, JointTrajectory out."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('trajplan', **kwargs)
        specs = {spec.name: spec for spec in PARAMETERS}
        moveit = self.declare_parameter('moveit_interfaces', False,
                                        _descriptor(specs.pop('moveit_interfaces'))).value
        for spec in specs.values():             # move_group checks collisions unless told not
            default = True if spec.name == 'collision_check' and moveit else spec.default
            self.declare_parameter(spec.name, default, _descriptor(spec))
        self._topic_description = ''                  # the last usable robot_description
        self._topic_semantic = ''                     # the last robot_description_semantic
        self._live = LiveScene()                      # obstacles from collision_objects
        self._settings = Settings.from_parameters(self._parameter_values())
        resolve_action(self, self._settings.controller_action)
        self._warn_ignored_joints(self._settings)
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

        self._goal_ids, self._call_ids = itertools.count(1), itertools.count(1)
        self._mailbox = Mailbox()
        self._counters = Counters()
        self._states = JointStateMonitor(self.get_logger().warning)
        self._log = QuickLogger(self.get_logger())      # the lines of every goal and call
        self._stopping = threading.Event()
        self._answer_lock = threading.Lock()
        self._publish_lock = threading.Lock()
        self._finished: collections.deque[tuple[Job, jobs.Outcome | None]] = (
            collections.deque())
        self._current: Job | None = None                        # the job being planned
        self._prepared: set[tuple] = set()          # the kinds of plan whose kernels are ready
        self._flushed = threading.Event()

        self._deliver = self.create_guard_condition(self._deliver_answers)
        self._flush = self.create_guard_condition(self._flushed.set)
        self._trajectories = self.create_publisher(JointTrajectory, 'joint_trajectory', 10)
        self._paths = self.create_publisher(Path, 'planned_path', 10)
        self._diagnostics = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self._results = self.create_publisher(DiagnosticStatus, outcomes.TOPIC, outcomes.QOS)
        self.create_subscription(Point, 'goal', self._on_goal, KEEP_ALL)
        self.create_subscription(PointStamped, 'clicked_point', self._on_clicked_point, KEEP_ALL)
        self.create_subscription(PoseStamped, 'goal_pose', self._on_goal_pose, KEEP_ALL)
        self.create_subscription(JointState, 'joint_states', self._on_joint_states,
                                 qos_profile_sensor_data)
        self.create_subscription(String, 'robot_description', self._on_description, LATCHED)
        self._markers = self.create_publisher(MarkerArray, 'collision_markers', LATCHED)
        self.create_subscription(String, 'robot_description_semantic', self._on_semantic, LATCHED)
        self.create_subscription(MarkerArray, 'collision_objects', self._on_collision_objects,
                                 KEEP_ALL)
        self._tf = listen(self)                   # frames beyond the URDF (None: no tf2)
        self._publish_markers(self._settings)
        self._execution: ActionExecution | None = None    # created when execution is action
        self._use_execution(self._settings)
        calls = ReentrantCallbackGroup()
        self.create_service(GetPlan, 'plan_trajectory', self._on_plan_call, qos_profile=KEEP_ALL,
                            callback_group=calls)
        self.create_service(GetPlan, 'compute_plan', self._on_compute_plan,
                            qos_profile=KEEP_ALL, callback_group=calls)
        self._move_group = self._offer_moveit(calls)
        self.create_timer(self._settings.diagnostic_period, self._publish_diagnostics)
        self._worker = threading.Thread(target=self._work, name='trajplan_worker', daemon=True)
        self._worker.start()

    # --- parameters -------------------------------------------------------------------------

    def _parameter_values(self) -> dict[str, Any]:
        return {p.name: p.value for p in self.get_parameters([s.name for s in PARAMETERS])}

    def _check_parameters(self, params: list[Parameter]) -> SetParametersResult:
        values = self._parameter_values()
        values.update({p.name: p.value for p in params})
        # start_positions is held to the chain when it, or the description, is being set
        strict = bool({p.name for p in params} & {'start_positions', 'robot_description'})
        try:
            self._check_live(Settings.from_parameters(
                values, self._topic_description, strict_start=strict,
                topic_semantic=self._topic_semantic))
            resolve_action(self, values['controller_action'])
            if values['execution'] == 'action' and self._execution is None:
                action_type()
            if values['moveit_interfaces'] != self.get_parameter('moveit_interfaces').value:
                raise ValueError('moveit_interfaces is read at start-up: start the node with '
                                 '--ros-args -p moveit_interfaces:=true')
        except Exception as exc:  # noqa: BLE001 - untrusted text: any fault is a refusal
            return SetParametersResult(successful=False, reason=_reason(exc))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, params: list[Parameter]) -> None:
        settings = Settings.from_parameters(self._parameter_values(), self._topic_description,
                                            strict_start=False,
                                            topic_semantic=self._topic_semantic)
        self._use_execution(settings)            # before a plan can take the settings
        self._use(settings)
        shown = ', '.join(f'{p.name}=<{len(p.value)} characters>' if p.name == 'robot_description'
                          else f'{p.name}={p.value}' for p in params)
        self.get_logger().info(f'parameters set for the next plan: {shown}')

    def _use_execution(self, settings: Settings) -> None:
        """Create the action client the first time execution is action (ValueError: no way)."""
        if settings.execution == 'action':
            self._action_execution()

    def _action_execution(self) -> ActionExecution:
        """Return the execution through the controller's action, made the first time."""
        if self._execution is None:
            self._execution = ActionExecution(self, self._report_execution,
                                              self._states.measured)
        return self._execution

    def _on_description(self, msg: String) -> None:
        """
        Build the arm from a robot_description message, or log why it is refused.

        A usable description is kept even while the parameter wins, for when it is cleared.
        """
        values = self._parameter_values()
        parameter = values['robot_description']
        try:
            settings = Settings.from_parameters({**values, 'robot_description': ''}, msg.data,
                                                strict_start=False,
                                                topic_semantic=self._topic_semantic)
            self._check_live(settings)
        except Exception as exc:  # noqa: BLE001 - untrusted text: any fault is a refusal
            self.get_logger().warning(f'robot_description refused: {_reason(exc)}; keeping '
                                      f'{jobs.describe_arm(self._settings)}')
            return
        self._topic_description = msg.data
        if parameter:
            self.get_logger().info('robot_description topic: kept for later; the '
                                   'robot_description parameter is set and wins')
            return
        self._use(settings)
        if settings.start_ignored:
            self.get_logger().warning(
                f'start_positions {list(values["start_positions"])} does not fit the '
                f'{settings.arm.n_joints}-joint chain: the start is all zeros until it is set '
                '(or joint_states arrive)')

    def _warn_ignored_joints(self, settings: Settings) -> None:
        """Warn once per settings of the joint limits' joints that the chain does not plan."""
        ignored = settings.request.motion.ignored_joints(settings.arm)
        if ignored:
            self.get_logger().warning(
                f"joint_limits_file: joints {', '.join(ignored)} are not in the planned chain "
                f"({', '.join(settings.arm.joint_names)}): ignored")

    def _use(self, settings: Settings) -> None:
        """Plan with ``settings`` from the next job; forget the old arm's states if it changed."""
        before = self._settings
        if (settings.request.motion, settings.arm.joint_names) != (
                before.request.motion, before.arm.joint_names):
            self._warn_ignored_joints(settings)
        settings = self._with_live_scene(settings)
        if settings.world is not before.world:
            self._publish_markers(settings)
        if settings.arm.same_as(before.arm):                  # e.g. only the speed changed
            self._settings = settings.planning_with(arm=before.arm)
            return
        self._settings = settings
        if settings.arm.joint_names != before.arm.joint_names:
            self._states.forget()
        self.get_logger().info(f'arm for the next plan: {jobs.describe_arm(settings)}')

    def _publish_markers(self, settings: Settings) -> None:
        """Publish the scene and the arm's spheres on collision_markers; log the check."""
        self._markers.publish(world_markers(settings.world, settings.base_frame,
                                            self.get_clock().now().to_msg()))
        w = settings.world
        self.get_logger().info(
            'collision check: off' if w is None else
            f'collision check: {len(w.arm.self_pairs)} link pairs ({len(w.arm.skip)} skipped, '
            f'{w.arm.skip_source}), {len(w.scene.obstacles)} obstacles, padding {w.padding} m')

    def _with_live_scene(self, settings: Settings) -> Settings:
        """Return ``settings`` whose scene has the obstacles received on topics too."""
        if settings.world is None or not self._live.received():
            return settings
        w = settings.world
        scene = Scene(w.scene.obstacles + self._live.received())
        return settings.planning_with(world=CollisionWorld(w.arm, scene, w.padding))

    def _check_live(self, settings: Settings) -> None:
        """
        Refuse settings whose scene cannot take the received obstacles (InvalidCollisionInput).

        Ids twice or too many obstacles, checked even while collisions are off; the world
        itself is built once, when the settings are used (``_with_live_scene``).
        """
        Scene((settings.world.scene.obstacles if settings.world is not None else ())
              + self._live.received())

    def _use_live(self, markers: dict[str, Obstacle] | None = None,
                  moveit: list[Obstacle] | None = None) -> bool:
        """
        Plan among these received obstacles from the next job; return whether it checks them.

        Raises InvalidCollisionInput (ids twice, too many) and keeps the scene as it was.
        """
        base = Settings.from_parameters(self._parameter_values(), self._topic_description,
                                        strict_start=False, topic_semantic=self._topic_semantic)
        before = self._live.obstacles, self._live.moveit
        if markers is not None:
            self._live.obstacles = markers
        if moveit is not None:
            self._live.moveit = tuple(moveit)
        try:
            self._check_live(base)
        except Exception:
            self._live.obstacles, self._live.moveit = before
            raise
        self._use(base)
        return base.world is not None

    def _on_semantic(self, msg: String) -> None:
        """Skip the pairs of an SRDF from now on (unless the parameter is set), or say why not."""
        try:
            settings = Settings.from_parameters(self._parameter_values(),
                                                self._topic_description, strict_start=False,
                                                topic_semantic=msg.data)
            self._check_live(settings)
        except Exception as exc:  # noqa: BLE001 - untrusted text: any fault is a refusal
            self.get_logger().warning(f'robot_description_semantic refused: {_reason(exc)}')
            return
        self._topic_semantic = msg.data
        self._use(settings)

    def _offer_moveit(self, calls: ReentrantCallbackGroup) -> MoveGroupServer | None:
        """Serve move_group's interfaces if ``moveit_interfaces`` (ValueError: cannot)."""
        if not self.get_parameter('moveit_interfaces').value:
            return None
        return MoveGroupServer(self, NodeHooks(
            lambda: self._settings, self._semantic, self._queue_call, self._action_execution,
            self._report_execution, self._header, self._call_ids, self._joint_angles,
            lambda obstacles: self._use_live(moveit=obstacles), self._pose_now, self._tf),
            calls, KEEP_ALL)

    def _pose_now(self, frame: str) -> np.ndarray:
        """Return a frame's pose in the base frame now, not waiting (ValueError: not known)."""
        return frame_pose(frame, self._settings, self._joint_angles(), self._tf)

    def _joint_angles(self) -> dict[str, float]:
        """Return the chain's joint angles now (joint_states, else the planned start)."""
        s = self._settings
        start = self._states.start(s.arm.joint_names, s.start).q
        return {name: float(q) for name, q in zip(s.arm.joint_names, start)}

    def _semantic(self) -> str:
        """Return the SRDF in use: the parameter's, else the topic's ('' if none)."""
        return self.get_parameter('robot_description_semantic').value or self._topic_semantic

    def _on_collision_objects(self, msg: MarkerArray) -> None:
        """Change the scene of the next plan by markers, or refuse them all with the reason."""
        try:
            obstacles = self._live.apply(msg, self._pose_now)
            self._use_live(markers=obstacles)
        except Exception as exc:  # noqa: BLE001 - untrusted input: any fault is a refusal
            self.get_logger().warning(f'collision_objects refused, scene kept: {_reason(exc)}')
            return
        frames = arrival_note((m.header.frame_id for m in msg.markers if m.action == m.ADD),
                              self._settings)
        self.get_logger().info(f'scene for the next plan: {len(obstacles)} obstacles from '
                               f'collision_objects{frames}')

    # --- inputs (executor thread) -----------------------------------------------------------

    def _on_goal(self, msg: Point) -> None:
        self._take_goal(Job(f'goal #{next(self._goal_ids)}',
                            jobs.message_goal(self._settings, (msg.x, msg.y, msg.z))))

    def _take_goal(self, job: Job) -> None:
        """Queue a topic goal (the newest waits), or refuse it when its frame is unknown."""
        self._counters.add('goals_received')
        problem = goal_problem(job.goal.frame, job.goal.orientation, self._settings, self._tf)
        if problem:
            self._counters.add('goals_failed')
            self._refused(job, problem)
            return
        self._log.debug(f'queued {job.label} {describe_goal(job.point)} m')
        superseded = self._mailbox.put_goal(job)
        if superseded is job:
            self._give_up(job)
        elif superseded is not None:
            self._counters.add('goals_superseded')
            reason = f'{job.label} arrived while planning'
            self._log.info(
                f'superseded {superseded.label} {describe_goal(superseded.point)} m: '
                f'{reason}')
            self._publish_outcome(superseded, 'superseded', reason)

    def _on_clicked_point(self, msg: PointStamped) -> None:
        p = msg.point
        self._take_goal(Job(f'clicked_point #{next(self._goal_ids)}', jobs.message_goal(
            self._settings, (p.x, p.y, p.z), msg.header.frame_id),
            stamp=(msg.header.stamp.sec, msg.header.stamp.nanosec)))

    def _on_goal_pose(self, msg: PoseStamped) -> None:
        p = msg.pose.position
        self._take_goal(Job(f'goal_pose #{next(self._goal_ids)}', jobs.message_goal(
            self._settings, (p.x, p.y, p.z), msg.header.frame_id, _quaternion(msg.pose)),
            stamp=(msg.header.stamp.sec, msg.header.stamp.nanosec)))

    def _on_joint_states(self, msg: JointState) -> None:
        self._states.update(msg.name, msg.position, self._settings.arm.joint_names)

    async def _on_plan_call(self, request: GetPlan.Request,
                            response: GetPlan.Response) -> GetPlan.Response:
        return await self._serve(request, response, plan_only=False)

    async def _on_compute_plan(self, request: GetPlan.Request,
                               response: GetPlan.Response) -> GetPlan.Response:
        return await self._serve(request, response, plan_only=True)

    async def _serve(self, request: GetPlan.Request, response: GetPlan.Response,
                     plan_only: bool) -> GetPlan.Response:
        """Answer a call of plan_trajectory, or of compute_plan (``plan_only``: never sent)."""
        s = self._settings
        p = request.goal.pose.position
        stamp = request.goal.header.stamp
        goal = jobs.message_goal(s, (p.x, p.y, p.z), request.goal.header.frame_id,
                                 _quaternion(request.goal.pose), request.tolerance)
        job = Job(f"{'compute_plan' if plan_only else 'service'} call #{next(self._call_ids)}",
                  goal, future=Future(), stamp=(stamp.sec, stamp.nanosec), plan_only=plan_only)
        response.plan = Path(header=self._header(s.base_frame))
        outcome = await self._queue_call(job, request_problem(request, s, self._tf))
        if outcome is not None and outcome.path is not None:
            response.plan = outcome.path
        return response

    async def _queue_call(self, job: Job, problem: str | None = None) -> jobs.Outcome | None:
        """
        Plan a service call's ``job`` in turn and return its outcome (None: not planned).

        ``problem``: why the call is refused before it is queued.
        """
        self._counters.add('calls_received')
        s = self._settings
        admission = None if problem else self._mailbox.put_call(job, s.max_queued_calls)
        outcome = None
        if problem:
            self._refused(job, problem)
        elif admission is Admission.QUEUED:
            outcome = await job.future
            job.taken.set()
        elif admission is Admission.FULL:
            self._refused(job, f'{s.max_queued_calls} calls are waiting already '
                               '(max_queued_calls)')
        else:
            self._give_up(job)
        self._counters.add('calls_answered')
        return outcome

    def _refused(self, job: Job, reason: str) -> None:
        self._log.warning(f'{job.label} {describe_goal(job.point)} m: refused: {reason}')
        self._publish_outcome(job, 'refused', reason)

    def _publish_outcome(self, job: Job, status: str, reason: str,
                         motion_time_s: float | None = None,
                         clearance: tuple[float, str] | None = None,
                         via_points: int | None = None) -> None:
        """Tell ``plan_results`` how ``job`` ended: from any thread, the first time only."""
        with self._answer_lock:
            if job.reported:
                return
            job.reported = True
            job.ended = job.ended if job.ended[0] else (status, reason)
        self._results.publish(self._status(job, status, reason, motion_time_s=motion_time_s,
                                           clearance=clearance, via_points=via_points))

    def _status(self, job: Job, status: str, message: str, **values: Any) -> DiagnosticStatus:
        """Build a status of ``job`` for ``plan_results`` (``outcomes.outcome_status``)."""
        return outcomes.outcome_status(f'{self.get_fully_qualified_name()}: {job.label}',
                                       'service call' if job.is_call else 'goal', job.stamp,
                                       job.point, status, message, **values)

    # --- planning (worker thread) and answers (executor thread) -----------------------------

    def _header(self, frame_id: str) -> Header:
        return Header(stamp=self.get_clock().now().to_msg(), frame_id=frame_id)

    def _work(self) -> None:
        self._prepare()
        # what exists now (modules, kernels, the node) lives as long as the process: out of the
        # collector's reach, no full collection walks it with the interpreter lock held
        gc.freeze()
        while (job := self._mailbox.take()) is not None:
            self._current = job
            try:
                self._handle(job)
            except Exception as exc:  # noqa: BLE001 - a bug must not end the planning thread
                reason = f'planning failed: {exc!r}'
                self.get_logger().error(f'{job.label} {describe_goal(job.point)} m: '
                                        f'{reason}')
                self._give_up(job, status='failed', reason=reason)
            self._current = None

    def _prepare(self) -> None:
        """
        Compile or load the kernels the settings' plans use, saying so; then log ``ready``.

        Goals and calls that come meanwhile wait in the mailbox: the service is offered at once,
        even while a first start compiles.
        """
        self._prepare_for(self._settings)
        s = self._settings
        r = s.request
        self.get_logger().info(f'ready: {jobs.describe_arm(s)}, {r.algorithm}, '
                               f'{r.angular_velocity} rad/s, {r.motion.describe()} profile')

    def _prepare_for(self, settings: Settings) -> None:
        """
        Make the kernels of plans with ``settings`` ready before one runs on the plan's clock.

        Once for each kind of plan (mode, pose goals, scene, profile, algorithm): other
        settings' kernels (another mode, a scene) are compiled or loaded when settings first
        need them.
        """
        r = settings.request
        pose = settings.goal_orientation == 'pose'
        kind = (r.goal.mode, pose, r.world is not None, r.motion.profile, r.algorithm)
        if kind in self._prepared:
            return
        requests = [r, r.replace(goal=r.goal.replace(mode=Mode.POSE))] if pose else [r]
        kernels = prepare(*requests, announce=self.get_logger().info)
        log = self.get_logger().info if kernels.compiled else self.get_logger().debug
        log(kernels.describe())
        self._prepared.add(kind)

    def _handle(self, job: Job) -> None:
        outcome = self._plan(job)
        if job.is_call:
            self._answer(job, None if self._stopping.is_set() else outcome)
            # the answer goes out first: publishing now would compete with its sending for
            # the interpreter lock, so give it a moment unless more work is waiting
            job.taken.wait(SHUTDOWN_STEP_S)
            self._mailbox.wait_for_work(ANSWER_GRACE_S)
        self._report(job, outcome)

    def _plan(self, job: Job) -> jobs.Outcome:
        """Plan one job into its messages and log line."""
        s = self._settings
        self._prepare_for(_as_planned(job, s))
        if s.execution == 'action':         # the controller's state: it is what moves first
            deadline = time.monotonic() + s.controller_timeout
            while not (self._states.wait_for(s.arm.joint_names, SHUTDOWN_STEP_S / 5)
                       or self._stopping.is_set() or time.monotonic() > deadline):
                pass
        start = self._states.start(s.arm.joint_names, s.start)
        if job.start_state:
            start = start.given(job.start_state, 'the request')
        self._log.debug(f'planning {job.label} {describe_goal(job.point)} m')
        angles = dict(zip(s.arm.joint_names, start.q))
        outcome = jobs.run(job, s, start, self._header(s.base_frame), self._stopping.is_set,
                           lambda frame: frame_pose(frame, s, angles, self._tf,
                                                    job.stamp or (0, 0), s.transform_timeout,
                                                    self._stopping.is_set))
        if outcome.plan_time_s is not None:
            self._counters.plan_time(outcome.plan_time_s)
        if outcome.timed_out:
            self._counters.add('plans_timed_out')
        return outcome

    def _report(self, job: Job, outcome: jobs.Outcome) -> None:
        """Publish a successful plan and log every one; nothing is published at shutdown."""
        with self._publish_lock:
            if self._stopping.is_set() or not self._mark_counted(job):
                self._give_up(job)
                return
            if not job.is_call:
                self._counters.add('goals_planned' if outcome.succeeded else 'goals_failed')
            execution = outcome.settings.execution if outcome.succeeded else 'none'
            if not job.plan_only and execution != 'none':
                self._send(job, outcome)
            # after the trajectory: a caller told "succeeded" finds it published
            self._publish_outcome(job, outcome.status, outcome.reason, outcome.motion_time_s,
                                  outcome.clearance, outcome.via_points)
            if outcome.succeeded:
                self._log.info(outcome.log)
            else:
                self._log.warning(outcome.log)
            if not job.plan_only and execution == 'action':      # its statuses come after
                self._execute(job, outcome)

    def _send(self, job: Job, outcome: jobs.Outcome) -> None:
        """Publish a planned motion's trajectory (topic) and its tool path, if watched."""
        traj, s = outcome.trajectory, outcome.settings
        if s.execution == 'topic':               # the action's controller tells its state
            self._trajectories.publish(trajectory_msg(traj))
            self._states.trajectory_ended(traj.joint_names, traj.positions[-1].tolist())
        if self._paths.get_subscription_count():     # a long path costs time to convert
            self._paths.publish(outcome.path or path_msg(s.arm, traj, self._header(s.base_frame)))

    def _execute(self, job: Job, outcome: jobs.Outcome) -> None:
        """Hand a planned motion to the controller's action (``ros.execution``)."""
        traj, s = outcome.trajectory, outcome.settings
        self._execution.submit(Motion(job, resolve_action(self, s.controller_action),
                                      trajectory_msg(traj),
                                      dict(zip(traj.joint_names, traj.positions[-1].tolist())),
                                      outcome.start.tolist(), traj.duration,
                                      s.controller_timeout, s.start_tolerance))

    def _report_execution(self, job: Job, status: str, message: str,
                          execution: outcomes.Execution | None = None) -> None:
        """Publish and log one execution status of ``job``; an ERROR one is a warning."""
        if self._move_group is not None:
            self._move_group.execution_ended(job, status, message)
        msg = self._status(job, status, message, execution=execution or outcomes.Execution())
        self._results.publish(msg)
        log = self._log.warning if msg.level == DiagnosticStatus.ERROR else self._log.info
        log(f'{job.label} {describe_goal(job.point)} m: execution: {status}: {message}')

    def _mark_counted(self, job: Job) -> bool:
        """Mark ``job`` as logged and counted; False if it already was."""
        with self._answer_lock:
            first, job.counted = not job.counted, True
            return first

    def _give_up(self, job: Job, status: str = 'shut_down', reason: str = '') -> None:
        """
        End a job unplanned (shutting down, or a fault): answer a call empty, count a goal.

        At shutdown (no ``reason``) it logs why; a fault was logged already.
        """
        if not job.ended[0]:                  # what a MoveIt caller is told, before the answer
            job.ended = (status, reason or 'the planner is shutting down')
        if job.is_call:
            self._answer(job, None)
        if self._mark_counted(job):
            if not job.is_call:
                self._counters.add('goals_failed')
            if not reason:
                given = ('answered with a plan; not published' if job.planned_answer
                         else 'unplanned')
                reason = f'{given}: shutting down'
                self.get_logger().info(f'{job.label} {describe_goal(job.point)} m: {reason}')
        self._publish_outcome(job, status, reason or 'shutting down')   # unless told already

    def _answer(self, job: Job, outcome: jobs.Outcome | None) -> None:
        """Hand a call its answer (once), for the executor thread to complete its Future."""
        with self._answer_lock:
            if job.answered:
                return
            job.answered = True
            job.planned_answer = outcome is not None and outcome.succeeded
            self._finished.append((job, outcome))
        self._deliver.trigger()

    def _deliver_answers(self) -> None:
        while self._finished:
            job, outcome = self._finished.popleft()
            job.future.set_result(outcome)

    def _publish_diagnostics(self) -> None:
        waiting, oldest = self._mailbox.waiting()
        current = self._current
        if current is not None and current.is_call and not current.answered:
            oldest = max(oldest, time.monotonic() - current.queued_at)
        self._states.flush_repeats()
        self._diagnostics.publish(diagnostic_array(
            self.get_fully_qualified_name(), self._header(''), self._counters.snapshot(),
            waiting, oldest, self._counters.superseded_since_last_report(),
            self._states.counts()))

    # --- shutdown (main thread) -------------------------------------------------------------

    def join_worker(self, timeout: float) -> None:
        """Wait up to ``timeout`` s for the worker thread to end (after ``shut_down``)."""
        self._worker.join(timeout)

    def shut_down(self) -> None:
        """Stop intake and the running plan, answer every waiting call with an empty plan."""
        with self._publish_lock:
            self._stopping.set()
        for job in self._mailbox.close():
            self._give_up(job)
        self._worker.join(timeout=SHUTDOWN_STEP_S)       # the running plan stops at its next check
        current = self._current
        if current is not None:
            self._give_up(current)                       # still in one long iteration
        if self._execution is not None:                  # cancel what the controller executes
            if not self._execution.shut_down(4 * SHUTDOWN_STEP_S):
                self.get_logger().warning('the controller did not confirm the cancel in time')
        answered = threading.Event()
        for _ in range(int(SHUTDOWN_STEP_S / 0.01)):     # the answers go out on the executor
            snapshot = self._counters.snapshot()
            if snapshot['calls_answered'] >= snapshot['calls_received']:
                break
            answered.wait(0.01)
        self._flushed.clear()
        self._flush.trigger()                            # one more turn: the last send is done
        self._flushed.wait(SHUTDOWN_STEP_S)


def _reason(exc: Exception) -> str:
    """Return a refusal's one-line reason (a fault other than ValueError named by its type)."""
    text = str(exc).splitlines()[0] if str(exc) else ''
    return text if isinstance(exc, ValueError) else f'{type(exc).__name__}: {text}'


def _spin(executor: SingleThreadedExecutor, failure: list[BaseException]) -> None:
    try:
        executor.spin()
    except ExternalShutdownException:
        pass
    except Exception as exc:  # noqa: BLE001 - reported by main, which exits non-zero
        get_logger('trajplan').fatal(f'the executor failed: {exc!r}')
        failure.append(exc)


def main(args: list[str] | None = None) -> int:
    """Run the node until SIGINT or SIGTERM, then shut down without losing a call."""
    sys.setswitchinterval(SWITCH_INTERVAL_S)
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    try:
        node = PlannerNode()
    except (ValueError, ParameterException) as exc:
        get_logger('trajplan').fatal(f'invalid parameters: {exc}')
        rclpy.try_shutdown()
        return 2
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    failure: list[BaseException] = []
    spinner = threading.Thread(target=_spin, args=(executor, failure), name='trajplan_executor',
                               daemon=True)
    spinner.start()
    while spinner.is_alive() and not stop.wait(0.5):
        pass
    node.shut_down()
    node.join_worker(EXIT_WAIT_S)                  # its plan stops at its next check
    executor.shutdown(timeout_sec=EXIT_WAIT_S)
    spinner.join(timeout=EXIT_WAIT_S)
    node.destroy_node()
    rclpy.try_shutdown()
    code = 1 if failure else 0
    alive = [t.name for t in threading.enumerate()
             if t is not threading.main_thread() and t.is_alive()]
    if alive:
        # the interpreter's exit would stop a thread inside C or C++ code (rclpy's wait, LLVM
        # compiling a kernel) by unwinding it there: std::terminate, exit -6. Leave them be.
        get_logger('trajplan').warning(f"{', '.join(alive)} still running {EXIT_WAIT_S:g} s "
                                       'after shutdown: they end with the process')
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    return code


if __name__ == '__main__':
    sys.exit(main())
