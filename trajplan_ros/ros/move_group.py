# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
move_group's interfaces on the planner node (parameter ``moveit_interfaces``).

* ``plan_kinematic_path`` (moveit_msgs/srv/GetMotionPlan): a coroutine that queues the
  request as one of the node's calls and awaits its outcome (``ros.moveit_interfaces``
  translates both ways).
* ``execute_trajectory`` (ExecuteTrajectory action) and ``move_action`` (MoveGroup action: plan,
  then execute unless ``plan_only``), where control_msgs loads: coroutines that hand the
  trajectory to the node's ``ActionExecution`` and await its end, which ``execution_ended``
  sets from the node's report of each execution status.
* ``trajectory_execution_event`` (std_msgs/String): ``stop`` cancels every execution these
  interfaces started.
* ``compute_cartesian_path``: answered at once, PLANNING_FAILED.

Everything here runs on the node's executor thread; the planning is the node's worker's.
"""
from __future__ import annotations

from dataclasses import dataclass
import itertools
from typing import Any, Awaitable, Callable

from geometry_msgs.msg import PoseStamped
import numpy as np
from rclpy.callback_groups import CallbackGroup
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.task import Future
from std_msgs.msg import Header, String
from trajplan_ros.collision.scene import Obstacle
from trajplan_ros.planning import Goal
from trajplan_ros.ros import moveit_interfaces as moveit
from trajplan_ros.ros.collision_objects import MoveItObjects
from trajplan_ros.ros.execution import action_type, ActionExecution, resolve_action
from trajplan_ros.ros.job import Outcome
from trajplan_ros.ros.mailbox import Job
from trajplan_ros.ros.messages import pose_msg
from trajplan_ros.ros.settings import Settings
from trajplan_ros.ros.transforms import arrival_note, Transforms

__all__ = ['MoveGroupServer', 'NodeHooks']


@dataclass(frozen=True)
class NodeHooks:
    """What the MoveIt interfaces use of the planner node."""

    settings: Callable[[], Settings]                    # the settings in force
    semantic: Callable[[], str]                         # the SRDF in use ('' if none)
    queue_call: Callable[[Job, str | None], Awaitable[Outcome | None]]   # plan a call in turn
    execution: Callable[[], ActionExecution]            # the execution through the action
    report: Callable[[Job, str, str], None]             # an execution status for plan_results
    header: Callable[[str], Header]                     # a header stamped now in a frame
    call_ids: itertools.count                           # the node's call numbers
    joint_angles: Callable[[], dict[str, float]]        # the chain's angles now, by name
    #: plan among these world objects from the next job (InvalidCollisionInput: refused);
    #: returns whether collisions are checked
    use_objects: Callable[[list[Obstacle]], bool]
    pose_now: Callable[[str], np.ndarray]              # a frame's pose in the base frame now
    transforms: Transforms | None                       # tf2's, for frames beyond the URDF


class MoveGroupServer:
    """Serve move_group's interfaces for MoveIt's clients (ValueError: moveit_msgs missing)."""

    def __init__(self, node: Node, hooks: NodeHooks, calls: CallbackGroup,
                 qos: QoSProfile) -> None:
        self._node, self._hooks = node, hooks
        self._msg, srv = moveit.moveit_types()
        self._codes = self._msg.MoveItErrorCodes
        self._said: set[str] = set()              # request fields said to be ignored
        #: the executions running, by goal id: their job and the future of their end
        self._executions: dict[bytes, tuple[Job, Future]] = {}
        self._objects = MoveItObjects()
        node.create_subscription(self._msg.CollisionObject, 'collision_object',
                                 self._on_collision_object, qos)
        node.create_service(srv.GetPlanningScene, 'get_planning_scene', self._on_get_scene)
        node.create_service(srv.ApplyPlanningScene, 'apply_planning_scene', self._on_apply_scene)
        node.create_service(srv.GetMotionPlan, 'plan_kinematic_path', self._on_motion_plan,
                            qos_profile=qos, callback_group=calls)
        node.create_service(srv.GetCartesianPath, 'compute_cartesian_path',
                            self._on_cartesian_path)
        node.create_service(srv.GetPositionIK, 'compute_ik', self._on_ik, qos_profile=qos,
                            callback_group=calls)
        node.create_service(srv.GetPositionFK, 'compute_fk', self._on_fk)
        served = ('plan_kinematic_path, compute_ik, compute_fk, collision_object, '
                  'get_planning_scene, apply_planning_scene')
        try:
            action_type()                                # executes through control_msgs
        except ValueError as exc:
            node.get_logger().warning(f'execute_trajectory and move_action not served: {exc}')
        else:
            from moveit_msgs.action import ExecuteTrajectory, MoveGroup
            from rclpy.action import ActionServer, CancelResponse

            self._execute_type, self._move_type = ExecuteTrajectory, MoveGroup
            ActionServer(node, ExecuteTrajectory, 'execute_trajectory', self._on_execute,
                         cancel_callback=self._on_cancel, callback_group=calls)
            ActionServer(node, MoveGroup, 'move_action', self._on_move,
                         cancel_callback=self._on_cancel, callback_group=calls)
            self._cancel_accepted = CancelResponse.ACCEPT
            node.create_subscription(String, 'trajectory_execution_event', self._on_event, 10)
            served += ', execute_trajectory, move_action, trajectory_execution_event'
        node.get_logger().info(f"MoveIt's interfaces ready: {served} "
                               '(compute_cartesian_path answers that it is not offered)')

    # --- planning ---------------------------------------------------------------------------

    async def _on_motion_plan(self, request: Any, response: Any) -> Any:
        """Answer plan_kinematic_path (``ros.moveit_interfaces``)."""
        await self._plan('plan_kinematic_path call', request.motion_plan_request,
                         response.motion_plan_response)
        return response

    async def _plan(self, kind: str, asked: Any, response: Any,
                    cancelled: Callable[[], bool] = lambda: False) -> str:
        """
        Plan a MotionPlanRequest into a MotionPlanResponse; return the code's name.

        Each goal region is planned as a call of its own, in turn, with its share of
        ``allowed_planning_time``, until ``cancelled``; the fastest answers.
        """
        s = self._hooks.settings()
        label = f'{kind} #{next(self._hooks.call_ids)}'
        try:
            jobs = moveit.goal_jobs(label, asked, s, self._hooks.semantic(), self._say_ignored,
                                    self._hooks.transforms is not None)
        except moveit.Refusal as exc:
            await self._refuse(label, exc)
            moveit.fill_response(response, None, (exc.code, str(exc)), s, asked.group_name,
                                 self._hooks.header(s.base_frame), self._codes)
            return exc.code
        outcomes = []
        for job in jobs:
            if outcomes and cancelled():
                break                        # the regions planned so far answer
            outcomes.append(await self._hooks.queue_call(job, None))
        best, code = moveit.fastest(outcomes, jobs[:len(outcomes)])
        moveit.fill_response(response, outcomes[best], code, s, asked.group_name,
                             self._hooks.header(s.base_frame), self._codes)
        return code[0]

    async def _refuse(self, label: str, refusal: moveit.Refusal) -> None:
        """Count and report a refused request as the node does its calls."""
        await self._hooks.queue_call(Job(label, Goal(), future=Future()), str(refusal))

    def _say_ignored(self, field: str) -> None:
        if field not in self._said:
            self._said.add(field)
            why = ('raised to min_planning_time' if field in ('allowed_planning_time', 'timeout')
                   else 'ignored: give world objects on collision_object'
                   if field.endswith('planning_scene_diff') else
                   'ignored (one planner: this one)')
            self._node.get_logger().info(f'{field} is {why}; said once')

    async def _on_ik(self, request: Any, response: Any) -> Any:
        """Answer compute_ik: the joint goal the planner would move to from the seed."""
        s = self._hooks.settings()
        label = f'compute_ik call #{next(self._hooks.call_ids)}'
        ik = request.ik_request
        try:
            job = moveit.ik_job(label, ik, s, self._hooks.semantic(), self._say_ignored,
                                self._hooks.transforms is not None)
        except moveit.Refusal as exc:
            await self._refuse(label, exc)
            response.error_code = self._code(exc.code, str(exc))
            return response
        outcome = await self._hooks.queue_call(job, None)
        name, message = moveit.error_code(outcome, job)
        if name in ('GOAL_CONSTRAINTS_VIOLATED', 'PLANNING_FAILED'):
            name = 'NO_IK_SOLUTION'          # no pose there, or none the arm moves to freely
        response.error_code = self._code(name, message)
        if name == 'SUCCESS':
            state = response.solution.joint_state
            state.header = self._hooks.header(s.base_frame)
            seed = dict(zip(ik.robot_state.joint_state.name, ik.robot_state.joint_state.position))
            solved = dict(zip(s.arm.joint_names, map(float, outcome.result.joint_goal)))
            state.name = list(solved) + [n for n in seed if n not in solved]
            state.position = [solved.get(n, seed.get(n, 0.0)) for n in state.name]
        return response

    def _on_fk(self, request: Any, response: Any) -> Any:
        """Answer compute_fk: each link's pose in the request's frame at its robot state."""
        s = self._hooks.settings()
        try:
            poses = moveit.fk_poses(request, s, self._hooks.joint_angles())
        except moveit.Refusal as exc:
            response.error_code = self._code(exc.code, str(exc))
            return response
        header = self._hooks.header(request.header.frame_id or s.base_frame)
        for link, pose in zip(request.fk_link_names, poses):
            stamped = PoseStamped(header=header, pose=pose_msg(pose))
            response.pose_stamped.append(stamped)
            response.fk_link_names.append(link)
        response.error_code = self._code('SUCCESS', '')
        return response

    def _on_cartesian_path(self, request: Any, response: Any) -> Any:
        """Answer at once: straight-line tool paths are not what this planner plans."""
        response.error_code = self._codes(val=self._codes.PLANNING_FAILED, source=moveit.SOURCE,
                                          message='straight-line tool paths are not offered: '
                                                  'plan_kinematic_path plans the least-time '
                                                  'motion')
        return response

    # --- execution --------------------------------------------------------------------------

    async def _on_execute(self, goal: Any) -> Any:
        """Execute an ExecuteTrajectory goal through the controller's action; end it so."""
        name, message = await self._execute(goal, goal.request.trajectory.joint_trajectory,
                                            self._execute_type.Feedback)
        self._end(goal, name)
        return self._execute_type.Result(error_code=self._code(name, message))

    async def _on_move(self, goal: Any) -> Any:
        """Plan a MoveGroup goal, then execute it unless it is plan only; end it so."""
        feedback = self._move_type.Feedback
        goal.publish_feedback(feedback(state='PLANNING'))
        diff = goal.request.planning_options.planning_scene_diff
        if diff.world.collision_objects or diff.robot_state.attached_collision_objects:
            self._say_ignored('planning_options.planning_scene_diff')   # send them on topics
        planned = self._msg.MotionPlanResponse()
        name = await self._plan('move_action goal', goal.request.request, planned,
                                lambda: goal.is_cancel_requested)
        result = self._move_type.Result(
            error_code=planned.error_code, trajectory_start=planned.trajectory_start,
            planned_trajectory=planned.trajectory, planning_time=planned.planning_time)
        if name == 'SUCCESS' and goal.is_cancel_requested:
            name = 'PREEMPTED'
            result.error_code = self._code(name, 'cancelled before the execution')
        elif name == 'SUCCESS' and not goal.request.planning_options.plan_only:
            name, message = await self._execute(goal, planned.trajectory.joint_trajectory,
                                                feedback)
            result.error_code = self._code(name, message)
            if name == 'SUCCESS':
                result.executed_trajectory = planned.trajectory
        goal.publish_feedback(feedback(state='IDLE'))
        self._end(goal, name)
        return result

    async def _execute(self, goal: Any, trajectory: Any, feedback: type) -> tuple[str, str]:
        """Execute a joint trajectory for an action's goal; return the code's name and why."""
        s = self._hooks.settings()
        job = Job(f'execute_trajectory #{next(self._hooks.call_ids)}', Goal())
        try:
            motion = moveit.execution_motion(job, trajectory, s,
                                             resolve_action(self._node, s.controller_action))
        except moveit.Refusal as exc:
            self._hooks.report(job, 'refused', str(exc))
            return exc.code, str(exc)
        done = Future()
        key = bytes(goal.goal_id.uuid)
        self._executions[key] = (job, done)
        goal.publish_feedback(feedback(state='MONITOR'))
        execution = self._hooks.execution()
        execution.submit(motion)
        if goal.is_cancel_requested:               # asked before it was registered
            execution.cancel(job)
        status, message = await done
        self._executions.pop(key, None)
        return moveit.EXECUTION_CODES.get(status, 'CONTROL_FAILED'), message

    def execution_ended(self, job: Job, status: str, message: str) -> None:
        """Take an execution status of ``job``: any but ``accepted`` ends its goal."""
        for waiting_job, done in self._executions.values():
            if waiting_job is job and status != 'accepted' and not done.done():
                done.set_result((status, message))

    def _end(self, goal: Any, name: str) -> None:
        """End an action's goal as MoveIt does: SUCCEEDED only for SUCCESS."""
        if goal.is_cancel_requested and name == 'PREEMPTED':
            goal.canceled()
        elif name == 'SUCCESS':
            goal.succeed()
        else:
            goal.abort()

    def _code(self, name: str, message: str) -> Any:
        return self._codes(val=getattr(self._codes, name), message=message,
                           source=moveit.SOURCE)

    def _on_cancel(self, goal: Any) -> Any:
        job, _ = self._executions.get(bytes(goal.goal_id.uuid), (None, None))
        if job is not None:
            self._hooks.execution().cancel(job)
        return self._cancel_accepted

    def _on_event(self, msg: String) -> None:
        """Stop every execution on ``stop``, as move_group's trajectory execution does."""
        if msg.data != 'stop':
            self._node.get_logger().info(f'trajectory_execution_event {msg.data!r} ignored: '
                                         'only "stop" is known')
            return
        for job, _ in list(self._executions.values()):
            self._hooks.execution().cancel(job)
        self._node.get_logger().info(f'trajectory_execution_event stop: '
                                     f'{len(self._executions)} executions cancelled')

    # --- the planning scene -----------------------------------------------------------------

    def _on_collision_object(self, msg: Any) -> None:
        """Apply a world object, or refuse it with the reason (the scene stays as it was)."""
        problem = self._apply_objects([msg])
        if problem:
            self._node.get_logger().warning(f'collision_object refused, scene kept: {problem}')

    def _apply_objects(self, messages: list[Any], replace: bool = False) -> str | None:
        """Apply world objects (``replace``: instead of all held); return why not, or None."""
        held = self._objects.objects
        try:
            if replace:
                self._objects.objects = {}
            objects = self._objects.apply(messages, self._hooks.pose_now)
            checked = self._hooks.use_objects(self._objects.obstacles(objects))
        except Exception as exc:  # noqa: BLE001 - untrusted input: any fault is a refusal
            self._objects.objects = held
            text = str(exc).splitlines()[0] if str(exc) else ''
            return text if isinstance(exc, ValueError) else f'{type(exc).__name__}: {text}'
        self._objects.objects = objects
        log = self._node.get_logger()
        if checked:
            frames = arrival_note((m.header.frame_id for m in messages
                                   if m.operation in (m.ADD, m.APPEND, m.MOVE)),
                                  self._hooks.settings())
            log.info(f'scene for the next plan: {len(objects)} world objects from MoveIt{frames}')
        else:
            log.warning(f'{len(objects)} world objects from MoveIt held, but collision_check '
                        'is false: plans do not avoid them')
        return None

    def _on_get_scene(self, request: Any, response: Any) -> Any:
        """Answer get_planning_scene: the world objects, the robot's state, the names."""
        s = self._hooks.settings()
        scene = response.scene
        scene.name, scene.is_diff = 'trajplan_ros', False
        scene.robot_state.joint_state.header = self._hooks.header(s.base_frame)
        angles = self._hooks.joint_angles()
        scene.robot_state.joint_state.name = list(angles)
        scene.robot_state.joint_state.position = list(angles.values())
        scene.world.collision_objects = [placed.in_base(s.base_frame)
                                         for placed in self._objects.objects.values()]
        return response

    def _on_apply_scene(self, request: Any, response: Any) -> Any:
        """Apply a PlanningScene's world objects; a collision-matrix edit is refused."""
        scene = request.scene
        problem = None
        robot = scene.robot_state
        if scene.allowed_collision_matrix.entry_names or robot.attached_collision_objects:
            problem = ('collision-matrix edits and attached objects are not offered: give the '
                       'SRDF (robot_description_semantic) its disable_collisions pairs')
        else:
            problem = self._apply_objects(list(scene.world.collision_objects),
                                          replace=not scene.is_diff)
        if problem:
            self._node.get_logger().warning(f'apply_planning_scene refused, scene kept: '
                                            f'{problem}')
        response.success = problem is None
        return response
