# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The benchmark on a URDF chain (``trajplan bench --urdf``): goals, a reference, peers, scores.

Goals are the tool positions (in pose mode the tool frames) of seeded random in-limit
configurations (continuous joints within pi of 0); starts are q = 0 clipped into the limits, or
random in-limit configurations. These
arms have no exact minimum, so each goal gets a reference (``minimax_reference``): a multi-start
local solve of min t subject to fk(q) = goal (and the tool axis on the goal ray in radial mode,
along the approach direction, from above, in approach mode, the tool frame's orientation in pose
mode, where the drawn configuration is one more start),
|q_i - s_i| <= t_i^-1(t) (omega_i t under the servo law) and the limits, by scipy's SLSQP from
``starts`` random points. In
radial and approach modes a goal is kept only when the reference finds such a pose (approach:
goals on and above the base, z >= 0). The reference lives in
the bench only.

Every method runs on the same goals, starts and seeds. The position error of every answer is
measured by yourdfpy's forward kinematics of the URDF (not ours); a plan is reached when that
error is at most 1 um (and the axis within 1e-6 rad of the goal ray in radial mode, the
orientation within 1e-6 rad in pose mode), and
successful when it is reached with a motion time at most 0.1 % above the reference. The report
also counts answers that beat the reference by more than 0.1 % (where the reference is weak).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import time
from typing import Callable, Mapping, Sequence
import warnings

import numpy as np

from trajplan_ros.kinematics import ArmModel
from trajplan_ros.kinematics.rotations import quaternions, rotation_matrix
from trajplan_ros.kinematics.urdf_import import joints_between, read_urdf
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.motion.time_law import joint_reach, SERVO
from trajplan_ros.search.goal import DEFAULT_AXIS_TOLERANCE, Goal, InvalidRequest, Mode, TOP_DOWN
from trajplan_ros.search.objective import Objective
from trajplan_ros.search.region import Region
from trajplan_ros.tools.bench.methods import Answer, Method
from trajplan_ros.tools.bench.report import format_table
from trajplan_ros.tools.bench.runner import SUCCESS_AXIS_ERROR, SUCCESS_ERROR, SUCCESS_GAP

__all__ = ['ChainCase', 'ChainResults', 'IndependentFk', 'draw_chain_cases', 'format_chain',
           'ikpy_method', 'local_minimax', 'minimax_reference', 'region_cases', 'region_minimax',
           'region_reference', 'run_chain', 'tolerance_region']


@dataclass(frozen=True)
class ChainCase:
    """One goal: where to go, from where, the plans' seed and the reference's time and pose."""

    goal: np.ndarray
    start: np.ndarray
    seed: int
    reference_time: float
    reference_q: np.ndarray
    orientation: np.ndarray | None = None     # pose mode: the tool frame's quaternion


def _into_box(obj: Objective, x: np.ndarray) -> np.ndarray:
    """Return joint angles x turned by whole turns into the search box where it is a turn."""
    turn = obj.upper - obj.lower >= 2.0 * np.pi - 1e-12
    return np.clip(np.where(turn, obj.lower + np.mod(x - obj.lower, 2.0 * np.pi), x),
                   obj.lower, obj.upper)


def _box(arm: ArmModel) -> tuple[np.ndarray, np.ndarray]:
    """Return the joint limits, with a continuous joint's taken as [-pi, pi]."""
    return (np.where(np.isfinite(arm.lower), arm.lower, -np.pi),
            np.where(np.isfinite(arm.upper), arm.upper, np.pi))


def minimax_reference(obj: Objective, rng: np.random.Generator, starts: int = 24,
                      also: np.ndarray | None = None) -> tuple[float, np.ndarray | None]:
    """
    Return the least motion time SLSQP finds from ``starts`` random points and the start.

    Also return its joint goal. The start (clipped into the search box) is one more point: the
    fastest joint goal can lie in a narrow basin beside it, which random points miss (a Panda
    goal at 2.09 s, where 48 random points found 7.34 s). The problem is min t over (x, t)
    subject to c(x) = 0 (``Objective.residuals``), t_i^-1(t) >= |x_i - s_i| and the search
    box; a solve counts when its error is below 1e-9 m (and, in radial mode, its axis within
    1e-9 rad of the goal ray). The search box is the objective's (one turn for a joint with a
    wider range). ``also``: more points to start from (planned joints). (inf, None) when no
    solve counts.
    """
    best_time, best = np.inf, None
    start = np.clip(obj.start[: obj.lower.size], obj.lower, obj.upper)
    more = np.empty((0, obj.lower.size)) if also is None else np.atleast_2d(also)
    for x0 in np.vstack((rng.uniform(obj.lower, obj.upper, (starts, obj.lower.size)), start,
                         more)):
        x = local_minimax(obj, x0)
        t = np.inf if x is None else obj.motion_time(x[None])[0]
        if t < best_time:
            best_time, best = t, x
    return best_time, best


def local_minimax(obj: Objective, x0: np.ndarray) -> np.ndarray | None:
    """
    Return SLSQP's solution of the reference problem from x0, or None when it fails.

    SLSQP fails on redundant equalities (more conditions, the residuals the joints can change,
    than their rank: ``_moving_rows``), and can where the solutions are isolated points (the
    rank equals the joints that can move the tool). There they have no time to trade along
    them: a bounded least-squares solve finds the point instead (a joint that cannot move the
    tool stays at its start).
    """
    from scipy.optimize import least_squares, minimize

    m, s = obj.lower.size, obj.start[: obj.lower.size]
    rows, rank, idle = _moving_rows(obj)

    def residuals(z: np.ndarray) -> np.ndarray:
        return rows @ obj.residuals(obj.tool(z[None, :m]))[0]

    def jacobian(z: np.ndarray) -> np.ndarray:
        d = obj.tool_jacobian(z[None, :m])
        jac = rows @ obj.linear_residuals(*(j[0].T for j in d.jacobians())).T   # (rows, m)
        return np.hstack((jac, np.zeros((jac.shape[0], 1))))

    x = None
    if len(rows) <= rank:
        reach = _reach(obj)

        def slack(z: np.ndarray) -> np.ndarray:          # t_i^-1(t) -+ (x - s) >= 0
            ahead = reach(z[-1])[0]
            return np.concatenate((ahead - (z[:m] - s), ahead + (z[:m] - s)))

        def slack_jacobian(z: np.ndarray) -> np.ndarray:
            rate = reach(z[-1])[1][:, None]
            return np.vstack((np.hstack((-np.eye(m), rate)), np.hstack((np.eye(m), rate))))

        constraints = [{'type': 'eq', 'fun': residuals, 'jac': jacobian},
                       {'type': 'ineq', 'fun': slack, 'jac': slack_jacobian}]
        bounds = list(zip(obj.lower, obj.upper)) + [(0.0, obj.longest_time)]
        z0 = np.append(x0, obj.motion_time(x0[None])[0])
        x = _on_goal(obj, minimize(lambda z: z[-1], z0, jac=lambda z: np.eye(m + 1)[-1],
                                   method='SLSQP', bounds=bounds, constraints=constraints,
                                   options={'maxiter': 200, 'ftol': 1e-12}).x[:m])
    if x is None and rank == m - np.count_nonzero(idle):
        x = _on_goal(obj, least_squares(residuals, np.where(idle, s, x0),
                                        jac=lambda z: jacobian(z)[:, :m],
                                        bounds=(obj.lower, obj.upper), xtol=1e-15, ftol=1e-15,
                                        gtol=1e-15).x)
    return x


def region_minimax(obj: Objective, x0: np.ndarray, region: Region) -> np.ndarray | None:
    """
    Return SLSQP's least-time joint goal inside ``region`` about ``obj``'s goal from x0.

    Region radii of 0 hold that part exactly (the position residuals the joints can change,
    or the axis's or orientation's residuals). Inside: |p - g| <= r_p; the angle of the tool
    axis to its target, or of the rotation to the goal orientation (``Objective.angle_errors``),
    at most r_a, by its cosine. Each inequality is scaled to a
    gradient of order one on its boundary. None when SLSQP ends outside the region.
    """
    from scipy.optimize import minimize

    m, s = obj.lower.size, obj.start[: obj.lower.size]
    count = 3 + len(obj.across_basis)
    held = np.flatnonzero(np.r_[np.full(3, region.position == 0.0),
                                np.full(count - 3, region.angle == 0.0)])
    reach = _reach(obj)
    rows = _moving_rows(obj, held)[0] if held.size else np.empty((0, 0))

    def tool(z: np.ndarray) -> np.ndarray:
        return obj.tool(z[None, :m])

    def inside(z: np.ndarray) -> np.ndarray:
        t = tool(z)
        out = [np.append(reach(z[-1])[0] - (z[:m] - s), reach(z[-1])[0] + (z[:m] - s))]
        if region.position > 0.0:
            d = t[0, 0] - obj.goal
            out.append([(region.position ** 2 - d @ d) / region.position])
        if region.angle > 0.0:
            out.append([(np.cos(obj.angle_errors(t)[0]) - np.cos(region.angle))
                        / np.sin(region.angle)])
        return np.concatenate(out)

    def exact(z: np.ndarray) -> np.ndarray:
        return rows @ obj.residuals(tool(z))[0][held]

    constraints = [{'type': 'ineq', 'fun': inside}]
    if held.size:
        constraints.append({'type': 'eq', 'fun': exact})
    bounds = list(zip(obj.lower, obj.upper)) + [(0.0, obj.longest_time)]
    z0 = np.append(x0, obj.motion_time(x0[None])[0])
    found = minimize(lambda z: z[-1], z0, jac=lambda z: np.eye(m + 1)[-1], method='SLSQP',
                     bounds=bounds, constraints=constraints,
                     options={'maxiter': 300, 'ftol': 1e-14})
    x = np.clip(found.x[:m], obj.lower, obj.upper)
    t = tool(np.append(x, 0.0))
    ok = (np.linalg.norm(t[0, 0] - obj.goal) <= max(region.position, 1e-9) * (1 + 1e-9)
          and (not obj.holds_axis
               or obj.angle_errors(t)[0] <= max(region.angle, 1e-9) * (1 + 1e-9)))
    return x if ok else None


def region_reference(obj: Objective, region: Region, rng: np.random.Generator,
                     starts: int, exact: np.ndarray) -> tuple[float, np.ndarray]:
    """
    Return the least motion time ``region_minimax`` finds, and its joint goal.

    From ``exact`` (the exact reference's joint goal, inside the region: the answer when none
    is faster), the start and ``starts`` random points.
    """
    best_time, best = float(obj.motion_time(exact[None])[0]), exact
    start = np.clip(obj.start[: obj.lower.size], obj.lower, obj.upper)
    for x0 in np.vstack((exact, start,
                         rng.uniform(obj.lower, obj.upper, (starts, obj.lower.size)))):
        x = region_minimax(obj, x0, region)
        t = np.inf if x is None else obj.motion_time(x[None])[0]
        if t < best_time:
            best_time, best = t, x
    return best_time, best


def _reach(obj: Objective) -> Callable[[float], tuple[np.ndarray, np.ndarray]]:
    """
    Return t -> (t_i^-1(t), its derivative) for each planned joint, from ``time_law``'s kernel.

    The derivative by a central difference (the reference's gradients need not be exact), but
    under the servo law, v_i.
    """
    law = obj.law

    def reach(t: float) -> tuple[np.ndarray, np.ndarray]:
        if law.kind == SERVO:
            return law.velocity * t, law.velocity
        h = 1e-7 * max(t, 1e-3)
        at = [[joint_reach(law, i, max(x, 0.0)) for i in range(obj.lower.size)]
              for x in (t, t - h, t + h)]
        return np.array(at[0]), (np.array(at[2]) - np.array(at[1])) / (2.0 * h)
    return reach


def tolerance_region(tolerances: Mapping[str, float], mode: Mode) -> Region:
    """Return the region of the given ``tolerances`` (0: exact, where not given)."""
    angle = 'orientation_tolerance' if mode is Mode.POSE else 'axis_tolerance'
    return Region(tolerances.get('tolerance', 0.0),
                  tolerances.get(angle, 0.0) if mode is not Mode.FREE else 0.0)


def axis_limit(mode: Mode) -> float:
    """
    Return the largest axis error that counts as reached in ``mode``.

    Radial: 1e-6 rad. Approach: the planner's default tolerance, as a small arm often cannot
    point exactly along the direction (its URDF's axes are off by micro-radians).
    """
    return DEFAULT_AXIS_TOLERANCE[mode.value] if mode is Mode.APPROACH else SUCCESS_AXIS_ERROR


def _on_goal(obj: Objective, x: np.ndarray) -> np.ndarray | None:
    """
    Return x clipped into the limits if it reaches the goal (within 1e-9), else None.

    The axis, when held, within 1e-9 rad in radial mode, within ``axis_limit`` in approach.
    """
    x = np.clip(x, obj.lower, obj.upper)
    tool = obj.tool(x[None])
    ok = np.linalg.norm(tool[0, 0] - obj.goal) <= 1e-9
    if obj.holds_axis:
        ok &= obj.angle_errors(tool)[0] <= (axis_limit(obj.mode) if obj.mode is Mode.APPROACH
                                            else 1e-9)
    return x if ok else None


def _moving_rows(obj: Objective, held: np.ndarray | None = None
                 ) -> tuple[np.ndarray, int, np.ndarray]:
    """
    Return a basis (rows) of the residuals the joints can change, their rank, the idle joints.

    ``held``: of those residuals only (indices; None: all).

    On a planar arm the position residual across the plane never changes: SLSQP fails on such
    a redundant equality ("singular matrix"), so the reference holds only the others (the
    goals lie in the plane). The rank of the constraint Jacobian is less than the planned
    joints where the solutions are not isolated, or where a joint cannot move the tool (the
    tool point on its axis: idle). All from the Jacobians at fixed random poses.
    """
    x = np.random.default_rng(0).uniform(obj.lower, obj.upper, (16, obj.lower.size))
    d = obj.tool_jacobian(x)
    jac = obj.linear_residuals(*(np.swapaxes(j, 1, 2) for j in d.jacobians()))  # (16, m, r)
    jac = jac if held is None else jac[..., held]
    u, sv, _ = np.linalg.svd(np.concatenate(jac, axis=0).T, full_matrices=False)
    rank = int(np.max(np.linalg.matrix_rank(jac, tol=1e-9 * sv[0])))
    idle = np.all(np.abs(jac) <= 1e-9 * sv[0], axis=(0, 2))
    moving = sv > 1e-9 * sv[0]
    rows = u[:, moving].T if not moving.all() else np.eye(len(sv))    # all: as they are
    return rows, rank, idle


def draw_chain_cases(arm: ArmModel, n: int, *, mode: Mode, random_starts: bool, seed: int,
                     starts: int = 24, progress: Callable[[], object] | None = None,
                     profile: MotionProfile | None = None) -> tuple[list[ChainCase], int]:
    """
    Draw ``n`` goals and their references (module docstring); also return how many were dropped.

    A goal is dropped when the reference finds no pose for it (radial mode: no radial pose;
    approach mode, from above: none, or the goal is below the base, z < 0).
    """
    rng = np.random.default_rng(seed)
    low, high = _box(arm)
    cases: list[ChainCase] = []
    dropped = 0
    while len(cases) < n:
        if dropped > 100 * n + 100:
            raise ValueError(f'the reference found a pose for only {len(cases)} of '
                             f'{len(cases) + dropped} goals in {mode.value} mode')
        q = rng.uniform(low, high, (2, arm.n_joints))
        frame = arm.frames(q[:1])[0, -1]
        goal = frame[:3, 3]
        orientation = quaternions(frame[None, :3, :3])[0] if mode is Mode.POSE else None
        if mode is Mode.APPROACH and goal[2] < 0.0:     # picks on and above the base's table
            dropped += 1
            continue
        start = q[1] if random_starts else np.clip(np.zeros(arm.n_joints), arm.lower, arm.upper)
        plan_seed = int(rng.integers(2 ** 31))
        try:
            obj = Objective(arm, Goal(goal, mode=mode, orientation=orientation), start,
                            profile=profile)
        except InvalidRequest:
            dropped += 1
            continue
        staged = obj.in_plane()
        drawn = _into_box(obj, q[0, :obj.arm.planned]) if mode is Mode.POSE else None
        best_time, best = minimax_reference(staged or obj, rng, starts, drawn)
        if best is None and staged is not None:        # the other component is off
            best_time, best = minimax_reference(obj, rng, starts)
        if best is None:
            dropped += 1
            continue
        cases.append(ChainCase(goal, start, plan_seed, best_time, obj.full(best)[0],
                               orientation))
        if progress is not None:
            progress()
    return cases, dropped


def region_cases(cases: Sequence[ChainCase], arm: ArmModel, mode: Mode, region: Region,
                 starts: int, profile: MotionProfile | None = None) -> list[ChainCase]:
    """
    Return the cases with references inside ``region`` (the goals' tolerances).

    Each is ``region_reference`` from the exact reference's joint goal and ``starts`` more
    points, drawn from the case's plan seed.
    """
    out = []
    for case in cases:
        obj = Objective(arm, Goal(case.goal, mode=mode, orientation=case.orientation),
                        case.start, profile=profile)
        time, best = region_reference(obj, region, np.random.default_rng(case.seed), starts,
                                      case.reference_q[: obj.arm.planned])
        out.append(replace(case, reference_time=time, reference_q=obj.full(best)[0]))
    return out


class IndependentFk:
    """The tool point and axes by yourdfpy's forward kinematics of the same URDF (not ours)."""

    def __init__(self, urdf: str, arm: ArmModel) -> None:
        import yourdfpy

        read_urdf(urdf)                      # the same checks before yourdfpy reads the file
        self._model = yourdfpy.URDF.load(urdf, build_scene_graph=True, load_meshes=False,
                                         load_collision_meshes=False)
        self._arm = arm

    def tool(self, q: np.ndarray, tool: np.ndarray) -> np.ndarray:
        """
        Return the tool point and axes (V, 3) in the base frame for joint angles q.

        ``tool`` (V, 3): the point and axes in the tip frame (``Objective.tool_frame``).

        trimesh's scene graph keeps a joint's old transform when the new one is within 1e-8 of
        it (``allclose``): a joint moved less than that since the last call (one answer on a
        limit, the next within 1e-8 rad of it) would give an error of up to some 1e-9 m. So
        every joint is first moved by 1 rad.
        """
        names = self._arm.joint_names
        self._model.update_cfg(dict(zip(names, np.asarray(q, dtype=float) + 1.0)))
        self._model.update_cfg(dict(zip(names, q)))
        tip = self._model.get_transform(frame_to=self._arm.tip_link,
                                        frame_from=self._arm.base_link)
        out = tool @ tip[:3, :3].T
        out[0] += tip[:3, 3]
        return out


@dataclass
class ChainResults:
    """One method's outcome on every case (arrays indexed by case)."""

    q: np.ndarray              # (n, n_joints) joint goals, rad
    error: np.ndarray          # position error by ``IndependentFk``, m
    axis_error: np.ndarray     # the mode's angle error (``Objective.angle_errors``), rad (0 free)
    gap: np.ndarray            # R / reference - 1
    seconds: np.ndarray        # wall time per plan, s
    axis_limit: float = SUCCESS_AXIS_ERROR     # the largest axis error reached (``axis_limit``)
    error_limit: float = SUCCESS_ERROR         # the largest position error reached

    @property
    def reached(self) -> np.ndarray:
        """Tell for each case whether the answer meets the goal (and the axis, if held)."""
        return (self.error <= self.error_limit) & (self.axis_error <= self.axis_limit)

    @property
    def success(self) -> np.ndarray:
        """Tell for each case whether the answer is reached within 0.1 % of the reference."""
        return self.reached & (self.gap <= SUCCESS_GAP)


def ikpy_method(urdf: str, arm: ArmModel) -> Method:
    """
    Return ikpy's inverse kinematics as a bench row for the chain of ``arm`` in ``urdf``.

    ikpy only reaches a pose (from the start as its initial guess); it does not minimise time.
    In radial mode it is asked for the tool z axis along the goal ray, in pose mode for the
    whole orientation.
    """
    path = [arm.base_link]                   # ikpy's elements: link, joint, link, ...
    for joint in joints_between(read_urdf(urdf), arm.base_link, arm.tip_link):
        path += [joint.name, joint.child]
    state: dict[str, object] = {}

    def solve(arm: ArmModel, mode: Mode, goal: np.ndarray, start: np.ndarray, seed: int,
              profile: MotionProfile, orientation: np.ndarray | None = None,
              tolerances: Mapping[str, float] | None = None) -> Answer:
        if 'chain' not in state:
            import ikpy.chain

            with warnings.catch_warnings():      # ikpy warns of every fixed joint it reads
                warnings.simplefilter('ignore', UserWarning)
                chain = ikpy.chain.Chain.from_urdf_file(urdf, base_elements=path,
                                                        symbolic=False)
                chain.active_links_mask = np.array([k.joint_type in ('revolute', 'continuous')
                                                    for k in chain.links])
            state['chain'] = chain
        chain = state['chain']
        initial = np.zeros(len(chain.links))
        initial[chain.active_links_mask] = start
        radial = {'target_orientation': goal / np.linalg.norm(goal),
                  'orientation_mode': 'Z'} if mode is Mode.RADIAL else {}
        if mode is Mode.APPROACH:
            radial = {'target_orientation': np.array(TOP_DOWN), 'orientation_mode': 'Z'}
        if mode is Mode.POSE:
            radial = {'target_orientation': rotation_matrix(orientation),
                      'orientation_mode': 'all'}
        found = np.asarray(chain.inverse_kinematics(goal, initial_position=initial, **radial))
        return Answer(found[chain.active_links_mask][: arm.planned],
                      joints=found[chain.active_links_mask])

    return Method('ikpy', 'ikpy inverse kinematics from the start (reaches; no time '
                  'minimisation)', solve, 'ikpy', 'ikpy.chain')


def _full(arm: ArmModel, method: Method, mode: Mode, case: ChainCase, profile: MotionProfile,
          tolerances: Mapping[str, float]) -> tuple[np.ndarray, float | None]:
    """Return the method's answer as every joint's angle, and its own time if it has one."""
    answer = method.solve(arm, mode, case.goal, case.start, case.seed, profile,
                          orientation=case.orientation, tolerances=tolerances)
    if answer.joints is not None:
        return answer.joints, answer.seconds
    if answer.plan is not None:
        return answer.plan.joint_goal, answer.seconds
    obj = Objective(arm, Goal(case.goal, mode=mode, orientation=case.orientation),
                    case.start, profile=profile)
    return obj.full(answer.x)[0], answer.seconds


def run_chain(methods: Sequence[Method], cases: Sequence[ChainCase], arm: ArmModel,
              mode: Mode, fk: IndependentFk, step: Callable[[], object] | None = None,
              profile: MotionProfile | None = None,
              tolerances: Mapping[str, float] | None = None) -> dict[str, ChainResults]:
    """
    Run every method on every case, taking turns goal by goal; score by ``fk``.

    ``tolerances``: the plans' ``tolerance``, ``axis_tolerance``, ``orientation_tolerance``
    (those given); an answer within them counts as reached.
    """
    n, tolerances = len(cases), dict(tolerances or {})
    region = tolerance_region(tolerances, mode)
    limits = (max(axis_limit(mode), region.angle * (1.0 + 1e-9)),
              max(SUCCESS_ERROR, region.position * (1.0 + 1e-9)))
    out = {m.name: ChainResults(np.full((n, arm.n_joints), np.nan),
                                *(np.full(n, np.nan) for _ in range(4)), *limits)
           for m in methods}
    for k, case in enumerate(cases):
        obj = Objective(arm, Goal(case.goal, mode=mode, orientation=case.orientation),
                        case.start, profile=profile)
        for method in methods:
            clock = time.perf_counter()
            q, seconds = _full(arm, method, mode, case, obj.profile, tolerances)
            res = out[method.name]
            res.seconds[k] = time.perf_counter() - clock if seconds is None else seconds
            res.q[k] = q
            tool = fk.tool(q, obj.tool_frame)
            res.error[k] = np.linalg.norm(tool[0] - case.goal)
            res.axis_error[k] = obj.angle_errors(tool[:, None])[0] if obj.holds_axis else 0.0
            moved = obj.motion_time(q[None, : obj.arm.planned])[0]
            res.gap[k] = moved / case.reference_time - 1.0
        if step is not None:
            step()
    return out


def format_chain(results: dict[str, ChainResults], cases: Sequence[ChainCase]) -> str:
    """Return the table: reached, success, both ways of beating by 0.1 %, time per plan."""
    lead = float(np.median(results['iepso'].seconds)) if 'iepso' in results else np.nan
    head = ('method', 'reached', 'success', 'beats ref', 'ref beats', 'worst error (m)',
            'median time', 'p99 time', 'x iepso')
    rows = []
    for name, r in results.items():
        reached = r.reached
        rows.append((name, f'{100 * reached.mean():.2f} %', f'{100 * r.success.mean():.2f} %',
                     str(int(np.sum(reached & (r.gap < -SUCCESS_GAP)))),
                     str(int(np.sum(reached & (r.gap > SUCCESS_GAP)))),
                     f'{np.max(r.error):.2g}', f'{1e3 * np.median(r.seconds):.1f} ms',
                     f'{1e3 * np.percentile(r.seconds, 99):.1f} ms',
                     f'{np.median(r.seconds) / lead:.1f}x' if np.isfinite(lead) else '-'))
    times = np.array([c.reference_time for c in cases])
    return format_table(head, rows) + (
        f'\nreference motion time: median {np.median(times):.4f} s; "beats ref" / "ref beats": '
        f'reached answers more than {100 * SUCCESS_GAP:g} % faster / slower than the reference')
