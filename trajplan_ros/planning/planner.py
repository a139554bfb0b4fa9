# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Direct trajectory planning (Lv et al. 2019): search the final joint angles, then move there.

``plan`` is the one entry point of the library, the ``trajplan`` command and the ROS node:

    >>> from trajplan_ros import plan
    >>> result = plan([0.151171, 0.19162, 0.172124], seed=1)
    >>> result.status, round(result.motion_time_s, 3)
    (<PlanStatus.SUCCEEDED: 'succeeded'>, 4.514)

The keywords are the fields of ``PlanRequest`` (``plan(PlanRequest(goal, ...))`` is the same).
Its tolerances make the goal a region: the search plans to the goal itself, then the plan moves
to the fastest point, axis or orientation within them (``search.region``).
A caller that must bound the search gives ``max_planning_time`` (s, on ``time.monotonic``)
and/or ``stop`` (a callable, e.g. true after Ctrl-C). The optimiser asks both after every
iteration (IEPSO also after every polish step); either ends the search with its best answer so
far, as TIMED_OUT or CANCELLED.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from enum import Enum
import time
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from trajplan_ros.collision.distances import ArmCollision, CollisionWorld
from trajplan_ros.collision.free_motion import check_motion, Clearance, StartLimits
from trajplan_ros.collision.scene import Obstacle, Scene
from trajplan_ros.collision.shapes import Shape
from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.kinematics.jit import warm_up, Warmup
from trajplan_ros.kinematics.rotations import quaternions
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.motion.time_law import TimeLaw
from trajplan_ros.motion.trajectory import path_points, path_trajectory, Trajectory
from trajplan_ros.planning.request import ALGORITHMS, PlanRequest
from trajplan_ros.search.detour import detour
from trajplan_ros.search.free_goal import free_joint_goal
from trajplan_ros.search.goal import Goal, InvalidRequest, Mode
from trajplan_ros.search.objective import DEFAULT_OMEGA, Objective
from trajplan_ros.search.optimize import Interrupt, OptimizeResult
from trajplan_ros.search.region import Region, within_tolerances

__all__ = ['ALGORITHMS', 'PlanRequest', 'PlanResult', 'PlanStatus', 'describe_goal',
           'describe_residual', 'plan', 'prepare']

#: The clock of ``max_planning_time`` (s), a module attribute so that tests can replace it.
_clock: Callable[[], float] = time.monotonic


class PlanStatus(str, Enum):
    """How a planning request ended."""

    SUCCEEDED = 'succeeded'        # reached within tolerance (the axis within axis_tolerance)
    NOT_REACHED = 'not_reached'    # optimised, but the best answer misses the goal or the axis
    REJECTED = 'rejected'          # refused before optimisation (bad goal or start)
    TIMED_OUT = 'timed_out'        # ended at max_planning_time, with the best answer so far
    CANCELLED = 'cancelled'        # ended by the caller's stop hook, with the best answer so far


@dataclass
class PlanResult:
    """Outcome of ``plan``; ``joint_goal`` is None only when the request was rejected."""

    status: PlanStatus
    message: str
    goal: np.ndarray
    start: np.ndarray | None
    joint_goal: np.ndarray | None = None
    position_error_m: float = float('nan')
    axis_error_rad: float = float('nan')          # angle of the tool axis to its target
    orientation_error_rad: float = float('nan')   # pose mode: angle of the rotation to the goal
    motion_time_s: float = float('nan')
    efficiency: float = float('nan')
    iterations: int = 0
    evaluations: int = 0
    plan_time_s: float = 0.0
    algorithm: str = 'iepso'
    mode: str = Mode.FREE.value
    angular_velocity: float = DEFAULT_OMEGA
    motion: MotionProfile = field(default_factory=MotionProfile)
    clearance_m: float = float('nan')             # least clearance of the motion (collisions)
    clearance_pair: str = ''                      # where it occurs
    via_points: tuple[np.ndarray, ...] = ()       # every joint's angles at each via point
    joint_names: tuple[str, ...] = ()             # the arm's, in the trajectory's order
    law: TimeLaw | None = field(default=None, repr=False)   # the whole arm's, for its motion
    history_efficiency: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    history_error: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)

    @property
    def omega(self) -> float:
        """Return ``angular_velocity`` (its earlier name, kept for callers)."""
        return self.angular_velocity

    @property
    def radial_error_rad(self) -> float:
        """Return ``axis_error_rad`` (its name from when only radial mode held the axis)."""
        return self.axis_error_rad

    @property
    def profile(self) -> MotionProfile:
        """Return ``motion`` (its earlier name, kept for callers)."""
        return self.motion

    @property
    def success(self) -> bool:
        """Return True when the goal was reached within the tolerance."""
        return self.status is PlanStatus.SUCCEEDED

    def trajectory(self, arm: ArmModel | None = None, sample_period: float = 0.1) -> Trajectory:
        """
        Return the joint trajectory from the start to the joint goal under ``motion``.

        Through the via points, if any, at rest at each (``motion.trajectory.path_trajectory``).

        The result knows its arm's joints and limits; ``arm`` (optional) is checked against it.
        """
        return path_trajectory(self.waypoints, self._law(arm), self.motion.timing,
                               sample_period=sample_period, joint_names=self.joint_names)

    def trajectory_points(self, arm: ArmModel | None = None, sample_period: float = 0.1) -> int:
        """Return how many points ``trajectory`` has, without building a long one."""
        return path_points(self.waypoints, self._law(arm), self.motion.timing, sample_period)

    @property
    def waypoints(self) -> list[np.ndarray]:
        """Return the motion's rests: the start, the via points, the joint goal."""
        return [self.start, *self.via_points, self.joint_goal]

    def _law(self, arm: ArmModel | None) -> TimeLaw:
        """Return the motion's time law; refuse a plan without a motion, or another arm."""
        if self.joint_goal is None or self.start is None or self.law is None:
            raise ValueError(f'no trajectory for a {self.status.value} plan: {self.message}')
        if arm is not None and tuple(arm.joint_names) != tuple(self.joint_names):
            raise ValueError(f'the plan is for joints {self.joint_names}, not {arm.joint_names}')
        return self.law

    def to_dict(self) -> dict[str, Any]:
        """Return a JSON-ready summary (the ``trajplan plan --json`` line); NaN becomes None."""
        def num(v: float) -> float | None:
            return float(v) if np.isfinite(v) else None

        return {
            'goal': [num(v) for v in self.goal],
            'success': self.success,
            'status': self.status.value,
            'joint_goal': None if self.joint_goal is None else [float(v) for v in self.joint_goal],
            'position_error_m': num(self.position_error_m),
            'axis_error_rad': num(self.axis_error_rad),
            'orientation_error_rad': num(self.orientation_error_rad),
            'motion_time_s': num(self.motion_time_s),
            'efficiency': num(self.efficiency),
            'iterations': self.iterations,
            'evaluations': self.evaluations,
            'plan_time_s': self.plan_time_s,
            'algorithm': self.algorithm,
            'mode': self.mode,
            'profile': self.motion.profile.value,
            'timing': self.motion.timing.value,
            'clearance_m': num(self.clearance_m),
            'clearance_pair': self.clearance_pair or None,
            'via_points': [[float(v) for v in via] for via in self.via_points],
            'message': self.message,
        }


def plan(request: PlanRequest | Sequence[float], start: Sequence[float] | None = None, *,
         stop: Callable[[], bool] | None = None, **settings: Any) -> PlanResult:
    """
    Plan the joint goal that reaches the request's goal from its start in least motion time.

    ``plan(PlanRequest(goal, ...))``, or, the same, ``plan(goal, start, **settings)`` with the
    request's fields as keywords (``PlanRequest``; the old names of ``RENAMED`` still work).
    Invalid goals and starts give a REJECTED result with the reason, never an exception;
    invalid settings raise ValueError (``PlanRequest.validate``). ``stop`` is asked after every
    iteration and polish step: True ends the search (Ctrl-C) as CANCELLED, as
    ``max_planning_time`` ends it as TIMED_OUT, each with its best answer so far.
    """
    if not isinstance(request, PlanRequest):
        request = PlanRequest.from_keywords(request, start, **settings)
    elif start is not None or settings:
        raise TypeError('give the start and settings in the PlanRequest, not beside it')
    request.validate()
    if stop is not None and not callable(stop):
        raise ValueError(f'stop must be None or a callable returning bool, got {stop!r}')
    r, goal = request, request.goal
    arm = r.planned_arm
    clock, interrupt = time.perf_counter(), _interrupt(r.max_planning_time, stop)
    common = {'goal': goal.position, 'algorithm': r.algorithm, 'mode': goal.mode.value,
              'angular_velocity': float(r.angular_velocity), 'motion': r.motion}
    if goal.frame not in ('', arm.base_link):
        return PlanResult(PlanStatus.REJECTED, f"the goal is in frame '{goal.frame}': plan "
                          f"takes goals in the base frame '{arm.base_link}' (Goal.moved)",
                          start=None, **{**common, 'goal': np.full(3, np.nan)})
    if goal.joint_goal is not None:
        return _to_joint_goal(r, clock, interrupt, common)
    try:
        start = r.start if r.start is not None else np.zeros(arm.n_joints)    # upright: q = 0
        obj = Objective(arm, goal, start, omega=r.angular_velocity, shaping=r.shaping,
                        profile=r.motion, start_margin=r.start_limit_margin)
        _check_world(r.world, obj.goal)
        common.update(joint_names=tuple(arm.joint_names),
                      law=r.motion.time_law(arm, r.angular_velocity))
    except InvalidRequest as exc:
        return PlanResult(PlanStatus.REJECTED, str(exc), start=None, **common)
    obj, found = _search(obj, r, interrupt)
    found = _fastest_within(obj, found, r)
    result = _outcome(obj, found, r, clock, common)
    if obj.start_notes:
        result.message += f"; {'; '.join(obj.start_notes)}: the motion brings it inside"
    if r.world is None or not result.success:
        return result
    return _collision_free(result, obj, r, clock, interrupt)


def _search(obj: Objective, r: PlanRequest,
            interrupt: Interrupt | None) -> tuple[Objective, OptimizeResult]:
    """
    Run the request's optimiser on ``obj``; return the objective searched and what it found.

    Approach mode on a pan-and-pitch arm first searches ``Objective.in_plane``: the tool
    axis's component in the goal's vertical plane alone. The answer stands when the other
    component is within ``axis_tolerance`` too (it is then the fastest of a larger set); else
    the search holds both.
    """
    def search(objective: Objective) -> OptimizeResult:
        return ALGORITHMS[r.algorithm](objective, population=r.population,
                                       max_iter=r.max_iterations, tol=r.convergence_precision,
                                       seed=r.seed, interrupt=interrupt, **r.optimizer_options)

    one = obj.in_plane()
    if one is not None:
        found = search(one)
        tool = one.tool(found.x[None])
        if (found.interrupted is not None
                or (np.linalg.norm(tool[0, 0] - obj.goal) <= r.goal.tolerance
                    and one.axis_angle(tool[1])[0] <= r.goal.axis_limit)):
            return one, found
    return obj, search(obj)


def _fastest_within(obj: Objective, found: OptimizeResult, r: PlanRequest) -> OptimizeResult:
    """
    Return the search's answer moved to the fastest joint goal inside the goal's tolerances.

    Only an answer that ``_status`` finds reached, not cut short, moves (``search.region``).
    """
    tool = obj.tool(found.x[None])
    angle = float(obj.angle_errors(tool)[0])          # NaN in free mode: not checked
    status, _ = _status(found, r, float(np.linalg.norm(tool[0, 0] - obj.goal)), angle,
                        obj.target_name)
    if status is not PlanStatus.SUCCEEDED:
        return found
    x = within_tolerances(obj, found.x, Region(r.goal.tolerance, r.goal.angle_limit))
    if x is found.x:
        return found
    ev = obj(x[None])
    return replace(found, x=x, fun=float(ev.efficiency[0]), motion_time=float(ev.motion_time[0]),
                   error=float(ev.error[0]))


def _to_joint_goal(r: PlanRequest, clock: float, interrupt: Interrupt | None,
                   common: dict[str, Any]) -> PlanResult:
    """
    Plan the motion to the request's joint goal, every joint moving (no search).

    Direct where it is free; else, with ``detours``, the fastest free motion found through via
    points to that same joint goal (``search.detour``), else NOT_REACHED. A goal outside the
    limits, or whose pose collides, is REJECTED with the reason.
    """
    arm = r.planned_arm.every_joint_planned()
    try:
        start = r.start if r.start is not None else np.zeros(arm.n_joints)
        q = _checked_joint_goal(r.planned_arm, r.goal.joint_goal, start)
        tip = arm.frames(q[None])[0, -1]
        pose = Goal(arm.tool(q[None])[0][0], Mode.POSE,
                    orientation=quaternions(tip[None, :3, :3])[0])
        obj = Objective(arm, pose, start, omega=r.angular_velocity, profile=r.motion,
                        start_margin=r.start_limit_margin)
        common.update(goal=obj.goal, joint_names=tuple(arm.joint_names),
                      law=r.motion.time_law(arm, r.angular_velocity))
    except InvalidRequest as exc:                # no tool point to name as the goal
        return PlanResult(PlanStatus.REJECTED, str(exc), start=None,
                          **{**common, 'goal': np.full(3, np.nan)})
    duration = float(obj.motion_time(q[None])[0])
    result = PlanResult(PlanStatus.SUCCEEDED, f'reached the joint goal in {duration:.4f} s of '
                        'motion', start=obj.start.copy(), joint_goal=q, position_error_m=0.0,
                        motion_time_s=duration, efficiency=float(obj(q[None]).efficiency[0]),
                        **common)
    if r.world is not None:
        _joint_goal_clear(result, obj, r, interrupt)
    result.plan_time_s = time.perf_counter() - clock
    return result


def _checked_joint_goal(arm: ArmModel, joint_goal: np.ndarray | Mapping[str, float],
                        start: np.ndarray) -> np.ndarray:
    """
    Return a joint goal as every joint's angle (InvalidRequest: why it cannot be one).

    Given the planned joints only, or angles by name, the others keep their ``start`` (within
    the limits).
    """
    if isinstance(joint_goal, Mapping):
        unknown = sorted(set(joint_goal) - set(arm.joint_names))
        if unknown:
            raise InvalidRequest(f"joint goal names {', '.join(unknown)}; the arm's joints are "
                                 f"{', '.join(arm.joint_names)}")
        try:
            q = np.clip(arm.full_start(start), arm.lower, arm.upper)
        except ValueError as exc:
            raise InvalidRequest(str(exc)) from None
        for name, angle in joint_goal.items():
            q[arm.joint_names.index(name)] = angle
        joint_goal = q
    try:
        q = arm.full_start(joint_goal)
    except ValueError as exc:
        raise InvalidRequest(str(exc).replace('a start', 'a joint goal')) from None
    if joint_goal.size < arm.n_joints:        # the held ones where they are, inside the limits
        q[joint_goal.size:] = np.clip(arm.full_start(start), arm.lower, arm.upper)[
            joint_goal.size:]
    if not np.all(np.isfinite(q)):
        raise InvalidRequest(f'joint goal has a non-finite angle: {q.tolist()}')
    outside = np.flatnonzero((q < arm.lower - 1e-9) | (q > arm.upper + 1e-9))
    if outside.size:
        i = int(outside[0])
        raise InvalidRequest(f'joint goal {arm.joint_names[i]} = {q[i]:.6g} rad is outside its '
                             f'limits [{arm.lower[i]:.4f}, {arm.upper[i]:.4f}]')
    return q


def _joint_goal_clear(result: PlanResult, obj: Objective, r: PlanRequest,
                      interrupt: Interrupt | None) -> None:
    """
    Keep a joint-goal plan whose motion is free, else route it around or say why not.

    A goal whose own pose collides is REJECTED, the pair in ``clearance_pair``.
    """
    world, q = r.world, result.joint_goal
    limits = StartLimits.at(world, obj.start)
    there = check_motion(world, q, q, result.law, r.motion.timing, True, limits)
    if not there.free:
        result.status, result.clearance_pair = PlanStatus.REJECTED, there.pair
        result.clearance_m = there.clearance
        result.message = f'the joint goal is in collision: {there.pair}'
        return
    clear = check_motion(world, obj.start, q, result.law, r.motion.timing, True, limits)
    if clear.free:
        _moved(result, obj, q, result.motion_time_s, result.efficiency, clear,
               reached='reached the joint goal')
        return
    rng = r.seed if isinstance(r.seed, np.random.Generator) else np.random.default_rng(r.seed)
    around = (detour(obj, world, result.law, r.motion.timing, q[None], rng, r.goal.tolerance,
                     interrupt, more_goals=False) if r.detours else None)
    if around is not None:
        _moved(result, obj, around.x, around.duration, np.nan if around.vias else
               result.efficiency, around.clearance, around.vias, 'reached the joint goal')
        return
    result.status = PlanStatus.NOT_REACHED
    result.clearance_m, result.clearance_pair = clear.clearance, clear.pair
    result.message = (f'the direct motion to the joint goal collides: {clear.pair}'
                      f'{_start_note(clear)}')
    if r.detours:
        result.message += '; no free motion through a via point found either'


def _check_world(world: CollisionWorld | None, goal: np.ndarray) -> None:
    """Refuse a goal inside an obstacle (InvalidRequest)."""
    inside = None if world is None else world.obstacle_at(goal)
    if inside is not None:
        raise InvalidRequest(f'goal {goal.tolist()} is inside obstacle {inside!r}')


def _collision_free(result: PlanResult, obj: Objective, r: PlanRequest, clock: float,
                    interrupt: Interrupt | None) -> PlanResult:
    """
    Return a reached plan moved to the fastest free motion found, or NOT_REACHED.

    The fastest free direct motion; where none is found and ``detours`` allows, the fastest
    free motion through a via point (``search.detour``).
    """
    world, seed = r.world, r.seed
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    x0 = result.joint_goal[:obj.arm.planned]
    found = free_joint_goal(obj, world, result.law, result.motion.timing, x0, rng,
                            r.goal.tolerance)
    result.clearance_m, result.clearance_pair = found.clearance.clearance, found.clearance.pair
    around = None
    if found.x is None and r.detours:
        around = detour(obj, world, result.law, result.motion.timing, found.goals, rng,
                        r.goal.tolerance, interrupt)
    if around is not None:
        efficiency = float(obj(around.x[None]).efficiency[0]) if not around.vias else np.nan
        _moved(result, obj, around.x, around.duration, efficiency, around.clearance, around.vias)
    elif found.x is None:
        result.status = PlanStatus.NOT_REACHED
        result.message = (f'every direct motion found collides: {found.clearance.pair}'
                          f'{_start_note(found.clearance)}')
        if r.detours:
            result.message += '; no free motion through a via point found either'
    else:
        _moved(result, obj, found.x, float(obj.motion_time(found.x[None])[0]),
               float(obj(found.x[None]).efficiency[0]), found.clearance)
    result.plan_time_s = time.perf_counter() - clock
    return result


def _start_note(clear: Clearance) -> str:
    """Return what the message says of a pair within the padding at the start ('' if none)."""
    return (f'; it starts within the padding ({clear.start_within}) and comes no closer'
            if clear.start_within else '')


def _moved(result: PlanResult, obj: Objective, x: np.ndarray, duration: float,
           efficiency: float, clear: Clearance, vias: tuple[np.ndarray, ...] = (),
           reached: str = 'reached') -> None:
    """Put the free motion to joint goal x (planned joints), through ``vias``, into ``result``."""
    joint_goal = obj.full(x)[0]
    p, _ = obj.arm.tool(joint_goal[None, :])
    result.joint_goal, result.via_points = joint_goal, vias
    result.position_error_m = float(np.linalg.norm(p[0] - obj.goal))
    result.motion_time_s, result.efficiency = duration, efficiency
    result.clearance_m, result.clearance_pair = clear.clearance, clear.pair
    via = f" via {len(vias)} point{'s' if len(vias) > 1 else ''}" if vias else ''
    result.message = (f'{reached} in {duration:.4f} s of motion{via}, error '
                      f"{describe_residual(result.position_error_m, 'm')}, "
                      f'{clear.describe()}{_start_note(clear)}')


def _interrupt(max_planning_time: float | None,
               stop: Callable[[], bool] | None) -> Interrupt | None:
    """
    Return the optimiser's interrupt for a time limit from now and a stop hook (None: neither).

    It asks ``stop`` first (CANCELLED), then the clock (TIMED_OUT once ``max_planning_time``
    has passed); it does nothing else, so a search it never ends is bit-identical.
    """
    if max_planning_time is None and stop is None:
        return None
    deadline = None if max_planning_time is None else _clock() + max_planning_time

    def interrupt() -> PlanStatus | None:
        if stop is not None and stop():
            return PlanStatus.CANCELLED
        if deadline is not None and _clock() >= deadline:
            return PlanStatus.TIMED_OUT
        return None
    return interrupt


#: Residuals below this (m or rad) are floating-point rounding of the kinematics: written as 0.
ROUNDING_FLOOR = 1e-12


def describe_goal(xyz: Sequence[float]) -> str:
    """Write a point as the node's and the command's log lines do (6 significant digits)."""
    return '(' + ', '.join(f'{v:.6g}' for v in xyz) + ')'


def describe_residual(value: float, unit: str) -> str:
    """Write a reached goal's error (``unit`` m or rad): 3 digits, or 0 below ROUNDING_FLOOR."""
    return f'0 {unit}' if abs(value) < ROUNDING_FLOOR else f'{value:.3g} {unit}'


def _status(found: OptimizeResult, limits: PlanRequest, pos_err: float, axis_err: float,
            target: str) -> tuple[PlanStatus, str]:
    """
    Return the status of a search and its one-line reason.

    ``axis_err``: the angle the mode holds (``Objective.angle_errors``) from ``target`` (its
    name): the tool axis's, or a pose's rotation; NaN in free mode.
    """
    if found.interrupted == PlanStatus.TIMED_OUT:
        return PlanStatus.TIMED_OUT, (f'planning ran past max_planning_time '
                                      f'{limits.max_planning_time:g} s; best position error '
                                      f'{pos_err:.3g} m')
    if found.interrupted == PlanStatus.CANCELLED:
        return PlanStatus.CANCELLED, 'planning stopped before the end'
    goal = limits.goal
    what, name = (('orientation', 'orientation_tolerance') if goal.mode is Mode.POSE
                  else ('axis', 'axis_tolerance'))
    axis = ('' if np.isnan(axis_err) else
            f", {what} {describe_residual(axis_err, 'rad')} from {target}")
    if pos_err > goal.tolerance:
        return PlanStatus.NOT_REACHED, (f'goal not reached: best position error {pos_err:.3g} m '
                                        f'is above the tolerance {goal.tolerance:.3g} m{axis}')
    if axis_err > goal.angle_limit:
        best, kind = (('orientation', 'pose') if goal.mode is Mode.POSE
                      else ('tool axis', f'{goal.mode.value} pose'))
        return PlanStatus.NOT_REACHED, (
            f'no {kind} found: the best {best} is {axis_err:.3g} rad from '
            f'{target} ({name} {goal.angle_limit:.3g} rad), position error '
            f'{pos_err:.3g} m')
    return (PlanStatus.SUCCEEDED,
            f'reached in {found.motion_time:.4f} s of motion, error '
            f"{describe_residual(pos_err, 'm')}{axis}")


def _outcome(obj: Objective, found: OptimizeResult, request: PlanRequest, clock: float,
             common: dict[str, Any]) -> PlanResult:
    """Return the result of a search: the joint goal, its errors, the status and a message."""
    joint_goal = obj.full(found.x)[0]
    tool = obj.tool(found.x[None])
    pos_err = float(np.linalg.norm(tool[0, 0] - obj.goal))
    axis_err = float(obj.axis_angle(tool[1])[0]) if obj.holds_axis else float('nan')
    turn_err = float(obj.angle_errors(tool)[0]) if obj.mode is Mode.POSE else float('nan')
    status, message = _status(found, request, pos_err,
                              turn_err if obj.mode is Mode.POSE else axis_err, obj.target_name)
    return PlanResult(
        status, message, start=obj.start.copy(), joint_goal=joint_goal, position_error_m=pos_err,
        axis_error_rad=axis_err, orientation_error_rad=turn_err,
        motion_time_s=found.motion_time, efficiency=found.fun,
        iterations=found.nit, evaluations=found.nfev, plan_time_s=time.perf_counter() - clock,
        history_efficiency=found.history_fun, history_error=found.history_error, **common)


#: The default settings, whose swarm size and iterations bound ``prepare``'s plans.
_DEFAULTS = PlanRequest((0.0, 0.0, 0.0))
#: A goal of the paper's arm that every mode reaches, for ``prepare``.
_WARM_UP_GOAL = (0.151171, 0.19162, 0.172124)


def _six_joint_arm() -> ArmModel:
    """
    Return a made-up six-joint arm (standard DH), for ``prepare``.

    In free mode its goals are reached on sets of two or more dimensions, where the polish takes
    the SQP step over active sets (``active_set``), which the paper's arm never does.
    """
    half = np.pi / 2
    return ArmModel.from_dh(a=(0.0, 0.3, 0.25, 0.0, 0.0, 0.0),
                            alpha=(half, 0.0, 0.0, half, -half, 0.0),
                            d=(0.1, 0.0, 0.0, 0.1, 0.08, 0.05), lower=[-np.pi] * 6,
                            upper=[np.pi] * 6)


def prepare(*requests: PlanRequest,
            announce: Callable[[str], object] | None = None) -> Warmup:
    """
    Compile or load the kernels that plans like ``requests`` use, so that none pays for it.

    Where that means compiling, ``announce`` is told so first, with about how long it takes;
    the result says what was done. Each request is planned once, to a goal its arm reaches (the
    tool at the middle of its joint limits; in pose mode with that orientation), with its mode
    and motion law, unbounded in time (a plan cut short would not reach the polish) but of the
    default swarm size and iterations (the kernels' types do not depend on them); with a
    world, the paper's arm once among a box instead of that world (whose goals may be blocked
    or need long detours). A kernel's machine code serves every arm.

    Without requests, every kernel: the paper's arm in each mode of a point goal, among a box,
    and a made-up six-joint arm in free mode and to a pose (the polish's SQP step), as the
    benchmarks and the command's first plan want. The node prepares its settings' requests
    only: the paper's arm without a scene needs no collision kernel.
    """
    def every_plan() -> None:
        for mode in (Mode.FREE, Mode.RADIAL, Mode.APPROACH):
            plan(_WARM_UP_GOAL, mode=mode, seed=0)
        plan(_WARM_UP_GOAL, seed=0, world=_warm_up_world())
        arm = _six_joint_arm()
        frame = arm.frames(np.full((1, 6), 0.4))[0, -1]
        plan(frame[:3, 3], arm=arm, mode=Mode.FREE, seed=0)
        plan(frame[:3, 3], arm=arm, mode=Mode.POSE, seed=0,
             orientation=quaternions(frame[None, :3, :3])[0])

    def these_plans() -> None:
        for request in requests:
            arm = request.planned_arm
            middle = (arm.lower + arm.upper) / 2
            frame = arm.frames(np.where(np.isfinite(middle), middle, 0.0))[0, -1]
            goal = request.goal
            orientation = (quaternions(frame[None, :3, :3])[0] if goal.mode is Mode.POSE
                           else goal.orientation)
            goal = goal.replace(position=frame[:3, 3], orientation=orientation, joint_goal=None,
                                frame='')
            plan(request.replace(goal=goal, start=None, seed=0, max_planning_time=None, world=None,
                                 population=_DEFAULTS.population,
                                 max_iterations=_DEFAULTS.max_iterations))
            if request.world is not None:
                plan(PlanRequest(_WARM_UP_GOAL, seed=0, motion=request.motion,
                                 world=_warm_up_world()))

    return warm_up(these_plans if requests else every_plan, announce,
                   recorded='first_plan' if requests else 'every_plan')


def _warm_up_world() -> CollisionWorld:
    """Return the paper's arm (its URDF's shapes) beside a box, for ``prepare``."""
    arm = paper_arm()
    model = ArmCollision.from_urdf(urdf_xml(arm, velocity=DEFAULT_OMEGA).encode(), arm)
    pose = np.eye(4)
    pose[:3, 3] = 0.12, -0.12, 0.1
    box = Obstacle('box', Shape.primitive('box', (0.05, 0.05, 0.2), pose, 'prepare'))
    return CollisionWorld(model, Scene((box,)))
