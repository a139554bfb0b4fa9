"""The ROS 2 planner node ``trajplan`` (executable ``planner_node``): a thin shell around ``plan``.

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

import array
import collections
import itertools
import math
import sys
import threading
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np
import rclpy
from geometry_msgs.msg import Point, PoseStamped
from nav_msgs.msg import Path
from nav_msgs.srv import GetPlan
from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.logging import get_logger
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from .arm import ArmModel, paper_arm
from .objective import Mode
from .planner import ALGORITHMS, DEFAULT_TOLERANCE, plan
from .trajectory import Trajectory

__all__ = ["PlannerNode", "main"]

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

#: arm.<key> parameters holding one number per joint: ArmModel argument -> description.
_ARM_VECTORS = {
    "a": "DH link lengths a_i, m", "alpha": "DH link twists alpha_i, rad",
    "d": "DH link offsets d_i, m",
    "offset": "joint angle offsets, rad (theta_i = sign_i q_i + offset_i)",
    "lower": "lower joint limits on q, rad", "upper": "upper joint limits on q, rad",
}


def _fmt(xyz: Sequence[float]) -> str:
    return "(" + ", ".join(f"{v:.6g}" for v in xyz) + ")"


def _real(lo: float, hi: float) -> list[FloatingPointRange]:
    return [FloatingPointRange(from_value=lo, to_value=hi, step=0.0)]


def _integer(lo: int, hi: int) -> list[IntegerRange]:
    return [IntegerRange(from_value=lo, to_value=hi, step=1)]


@dataclass(frozen=True)
class Settings:
    """The planning settings in force, built from (and checked against) the node's parameters."""

    arm: ArmModel
    omega: float
    mode: str
    algorithm: str
    population: int
    max_iter: int
    seed: int | None
    tolerance: float
    base_frame: str
    sample_period: float
    start: np.ndarray

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> "Settings":
        """Raise ValueError (InvalidArmModel for the arm) with the reason a value is refused."""
        arm = ArmModel(*(values[f"arm.{k}"] for k in ("a", "alpha", "d")),
                       sign=values["arm.sign"], offset=values["arm.offset"],
                       lower=values["arm.lower"], upper=values["arm.upper"],
                       joint_names=list(values["arm.joint_names"]), planned=values["arm.planned"])
        modes = [m.value for m in Mode]
        if values["mode"] not in modes:
            raise ValueError(f"mode must be one of {', '.join(modes)}, got {values['mode']!r}")
        if values["algorithm"] not in ALGORITHMS:
            raise ValueError(f"algorithm must be one of {', '.join(ALGORITHMS)}, "
                             f"got {values['algorithm']!r}")
        if not values["base_frame"]:
            raise ValueError("base_frame must not be empty")
        start = np.asarray(values["start_positions"], dtype=float)
        if start.shape != (arm.n_joints,) or not np.all(np.isfinite(start)):
            raise ValueError(f"start_positions needs {arm.n_joints} finite angles for the "
                             f"{arm.n_joints}-joint arm, got {list(start)} (change both at once)")
        return cls(arm=arm, omega=values["angular_velocity"], mode=values["mode"],
                   algorithm=values["algorithm"], population=values["population"],
                   max_iter=values["max_iterations"],
                   seed=None if values["seed"] < 0 else values["seed"],
                   tolerance=values["tolerance"], base_frame=values["base_frame"],
                   sample_period=values["sample_period"], start=start)


@dataclass
class _Job:
    """One goal for the worker. For a service call, ``done`` is set once ``path`` is final and
    ``answered`` once the service callback has taken it."""

    label: str
    goal: tuple[float, float, float]
    tolerance: float | None = None
    done: threading.Event | None = None
    answered: threading.Event | None = None
    path: Path | None = None


class _Mailbox:
    """Work for the planning thread: every service call in order, plus the newest topic goal."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._calls: collections.deque[_Job] = collections.deque()
        self._goal: _Job | None = None
        self._current: _Job | None = None
        self.closed = False

    def put_call(self, job: _Job) -> bool:
        """Queue a service call; False once closed (it will not be planned)."""
        with self._cond:
            if self.closed:
                return False
            self._calls.append(job)
            self._cond.notify()
            return True

    def put_goal(self, job: _Job) -> _Job | None:
        """Queue a topic goal; return the waiting goal it replaces, if any."""
        with self._cond:
            dropped, self._goal = self._goal, job
            self._cond.notify()
            return dropped

    def wait_for_work(self, timeout: float) -> None:
        """Return when there is work (or the mailbox is closed), or after ``timeout`` seconds."""
        with self._cond:
            self._cond.wait_for(lambda: self.closed or self._calls or self._goal is not None,
                                timeout=timeout)

    def take(self) -> _Job | None:
        """Block until there is work (service calls first); None once closed."""
        with self._cond:
            self._current = None
            while not self.closed and not self._calls and self._goal is None:
                self._cond.wait()
            if self.closed:
                return None
            if self._calls:
                self._current = self._calls.popleft()
            else:
                self._current, self._goal = self._goal, None
            return self._current

    def close(self) -> list[_Job]:
        """Stop handing out work; return the service calls still waiting for an answer."""
        with self._cond:
            self.closed = True
            self._cond.notify_all()
            waiting = [j for j in (self._current, *self._calls) if j is not None and j.done]
            self._calls.clear()
            return waiting


def _quaternions(rot: np.ndarray) -> np.ndarray:
    """Unit quaternions (x, y, z, w) of rotation matrices (N, 3, 3).

    Builds K = 4 q q^T (q = (w, x, y, z)) from the matrix entries and takes the row of its
    largest diagonal entry, which is well conditioned for every rotation.
    """
    m00, m11, m22 = rot[:, 0, 0], rot[:, 1, 1], rot[:, 2, 2]
    wx, wy, wz = rot[:, 2, 1] - rot[:, 1, 2], rot[:, 0, 2] - rot[:, 2, 0], rot[:, 1, 0] - rot[:, 0, 1]
    xy, xz, yz = rot[:, 0, 1] + rot[:, 1, 0], rot[:, 0, 2] + rot[:, 2, 0], rot[:, 1, 2] + rot[:, 2, 1]
    k = np.stack([
        np.stack([1 + m00 + m11 + m22, wx, wy, wz], axis=-1),
        np.stack([wx, 1 + m00 - m11 - m22, xy, xz], axis=-1),
        np.stack([wy, xy, 1 - m00 + m11 - m22, yz], axis=-1),
        np.stack([wz, xz, yz, 1 - m00 - m11 + m22], axis=-1)], axis=1)
    rows = np.arange(rot.shape[0])
    best = np.argmax(np.diagonal(k, axis1=1, axis2=2), axis=1)
    q = k[rows, best] / (2.0 * np.sqrt(k[rows, best, best]))[:, None]
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)          # w >= 0: one of the two equal quaternions
    return q[:, [1, 2, 3, 0]]


def trajectory_msg(traj: Trajectory) -> JointTrajectory:
    """The JointTrajectory of ``traj``; header.stamp stays zero ("start now")."""
    msg = JointTrajectory(joint_names=list(traj.joint_names))
    nanoseconds = np.round(traj.times * 1e9).astype(np.int64).tolist()
    points = []
    for ns, q, v in zip(nanoseconds, traj.positions, traj.velocities):
        point = JointTrajectoryPoint(positions=array.array("d", q), velocities=array.array("d", v))
        point.time_from_start.sec, point.time_from_start.nanosec = divmod(ns, 1_000_000_000)
        points.append(point)
    msg.points = points
    return msg


def path_msg(arm: ArmModel, traj: Trajectory, header: Header,
             blanks: list[PoseStamped] | None = None) -> Path:
    """The tool path of ``traj``: one pose per trajectory point, from forward kinematics.

    The poses share ``header`` and are filled in place, taken from ``blanks`` (new
    PoseStamped messages made in advance) while it lasts: building a message costs more than
    filling it.
    """
    tool = arm.frames(traj.positions)[:, -1]
    quats = _quaternions(tool[:, :3, :3])
    poses = []
    for (px, py, pz), (qx, qy, qz, qw) in zip(tool[:, :3, 3].tolist(), quats.tolist()):
        pose = blanks.pop() if blanks else PoseStamped()
        pose.header = header
        p, o = pose.pose.position, pose.pose.orientation
        p.x, p.y, p.z = px, py, pz
        o.x, o.y, o.z, o.w = qx, qy, qz, qw
        poses.append(pose)
    return Path(header=header, poses=poses)


class PlannerNode(Node):
    """Node ``trajplan``: goals and GetPlan calls in, JointTrajectory out."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__("trajplan", **kwargs)
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
        self._mailbox = _Mailbox()
        self._blanks: list[PoseStamped] = []     # worker thread only

        self._publisher = self.create_publisher(JointTrajectory, "joint_trajectory", 10)
        # a deep queue: every goal must reach _on_goal to be planned or logged as dropped
        self.create_subscription(Point, "goal", self._on_goal, 100)
        # best effort: matches joint_states publishers of either reliability
        self.create_subscription(JointState, "joint_states", self._on_joint_states,
                                 qos_profile_sensor_data)
        self.create_service(GetPlan, "plan_trajectory", self._on_plan_call,
                            callback_group=ReentrantCallbackGroup())
        self._worker = threading.Thread(target=self._work, name="trajplan_worker", daemon=True)
        self._worker.start()
        arm = self._settings.arm
        self.get_logger().info(
            f"ready: {arm.n_joints}-joint arm ({', '.join(arm.joint_names)}), "
            f"{self._settings.algorithm}, {self._settings.omega} rad/s")

    # --- parameters -------------------------------------------------------------------------

    def _declare_parameters(self) -> None:
        arm = paper_arm()

        def declare(name: str, value: Any, description: str, **extra: Any) -> None:
            self.declare_parameter(name, value, ParameterDescriptor(description=description, **extra))
            self._parameter_names.append(name)

        for key, meaning in _ARM_VECTORS.items():
            declare(f"arm.{key}", getattr(arm, key).tolist(), f"{meaning}, one per joint")
        declare("arm.sign", [int(s) for s in arm.sign],
                "joint direction signs (+1 or -1) in theta_i = sign_i q_i + offset_i")
        declare("arm.joint_names", list(arm.joint_names),
                "joint names, base to tool, as in joint_states and the published trajectory")
        declare("arm.planned", arm.planned, "how many leading joints are planned; the rest hold",
                integer_range=_integer(2, 7))
        declare("angular_velocity", 0.2, "servo angular velocity omega, rad/s",
                floating_point_range=_real(1e-3, 10.0))
        declare("mode", Mode.FREE.value, "free: position only; radial: eq. 12-13 orientation too",
                additional_constraints="one of: " + ", ".join(m.value for m in Mode))
        declare("algorithm", "iepso", "optimiser",
                additional_constraints="one of: " + ", ".join(ALGORITHMS))
        declare("population", 40, "particles per swarm", integer_range=_integer(2, 10000))
        declare("max_iterations", 1000, "iteration cap", integer_range=_integer(1, 1000000))
        declare("seed", 0, "random seed; -1: a fresh seed every plan",
                integer_range=_integer(-1, 2**31 - 1))
        declare("tolerance", DEFAULT_TOLERANCE,
                "largest position error that counts as reached, m (a GetPlan tolerance > 0 wins)",
                floating_point_range=_real(1e-12, 1.0))
        declare("base_frame", "base_link", "frame_id of the returned tool path")
        declare("sample_period", 0.1, "time between trajectory points, s",
                floating_point_range=_real(1e-3, 10.0))
        declare("start_positions", [0.0] * arm.n_joints,
                "start joint angles, rad, used until joint_states or a published trajectory "
                "tells the state")

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
        self.get_logger().info("parameters set for the next plan: " +
                               ", ".join(f"{p.name}={p.value}" for p in params))

    # --- inputs -----------------------------------------------------------------------------

    def _on_goal(self, msg: Point) -> None:
        job = _Job(f"goal #{next(self._goal_ids)}", (msg.x, msg.y, msg.z))
        dropped = self._mailbox.put_goal(job)
        if dropped is not None:
            self.get_logger().info(f"dropped {dropped.label} {_fmt(dropped.goal)} m: "
                                   f"superseded by {job.label} while planning")

    def _on_joint_states(self, msg: JointState) -> None:
        if not msg.position:
            return
        if len(msg.position) != len(msg.name):
            self.get_logger().warn(
                f"ignored joint_states: {len(msg.name)} names but {len(msg.position)} positions",
                throttle_duration_sec=5.0)
            return
        ours = set(self._settings.arm.joint_names)
        update = {n: float(q) for n, q in zip(msg.name, msg.position) if n in ours}
        bad = [n for n, q in update.items() if not math.isfinite(q)]
        if bad:
            self.get_logger().warn(f"ignored joint_states: non-finite position for {', '.join(bad)}",
                                   throttle_duration_sec=5.0)
            return
        with self._state_lock:
            self._measured.update(update)

    def _on_plan_call(self, request: GetPlan.Request,
                      response: GetPlan.Response) -> GetPlan.Response:
        p = request.goal.pose.position
        job = _Job(f"service call #{next(self._call_ids)}", (p.x, p.y, p.z),
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
        """Per joint: joint_states, else the last published trajectory's end, else the parameter."""
        with self._state_lock:
            known = {**self._last_end, **self._measured}
        return np.array([known.get(n, q) for n, q in zip(settings.arm.joint_names, settings.start)])

    def _work(self) -> None:
        while True:
            # make the next answer's poses while idle (a service answer waits on their making)
            self._blanks.extend(PoseStamped() for _ in range(BLANK_POSES - len(self._blanks)))
            if (job := self._mailbox.take()) is None:
                return
            try:
                self._plan(job)
            except Exception as exc:  # noqa: BLE001 - a core bug must not end the planning thread
                self.get_logger().error(f"{job.label} {_fmt(job.goal)} m: planning failed: {exc!r}")
            finally:
                self._answer(job)

    @staticmethod
    def _answer(job: _Job, path: Path | None = None) -> None:
        """Hand a service call its path (None: an empty plan) once, and wait until the service
        callback has taken it, so the answer goes out before this thread carries on."""
        if job.done is not None and not job.done.is_set():
            job.path = path
            job.done.set()
            job.answered.wait(timeout=1.0)

    def _plan(self, job: _Job) -> None:
        """Plan one job; on success answer the call (if any) with the tool path, then publish."""
        s = self._settings
        start = self._start(s)
        where = f"{job.label} {_fmt(job.goal)} m from q = {_fmt(start)} rad"
        self.get_logger().debug(f"planning {where}")
        result = plan(job.goal, start, arm=s.arm, mode=s.mode, algorithm=s.algorithm,
                      omega=s.omega, tolerance=job.tolerance or s.tolerance, seed=s.seed,
                      population=s.population, max_iter=s.max_iter)
        took = f"planned in {1e3 * result.plan_time_s:.3f} ms"
        if not result.success:
            self._answer(job)
            optimised = f"; {took}" if result.joint_goal is not None else ""
            self.get_logger().warn(f"{where}: {result.status.value}: {result.message}{optimised}")
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
        self.get_logger().info(f"{where}: {result.message}; {took}; published {len(traj.times)} "
                               f"points over {traj.duration:.3f} s")

    def destroy_node(self) -> None:
        """Answer the service calls still waiting with an empty plan, then destroy the node.

        A plan in progress cannot be interrupted: the daemon worker thread ends with the process.
        """
        waiting = self._mailbox.close()
        for job in waiting:
            if self.context.ok():     # after Ctrl-C or SIGTERM, /rosout is gone already
                self.get_logger().info(f"shutting down: {job.label} {_fmt(job.goal)} m unplanned")
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
        get_logger("trajplan").fatal(f"invalid parameters: {exc}")
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


if __name__ == "__main__":
    sys.exit(main())
