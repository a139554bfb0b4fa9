# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The ``trajplan figures`` subcommand: the paper's figures, redrawn from runs of this package.

Every figure comes from the paper's experiment (its target from q = 0, Table 4 settings) with
the seed ``--seed``; IEPSO appears twice, as this package runs it and as published (one swarm,
no polish, ``bench.methods.METHODS['iepso-paper']``):

* fig03_efficiency.png, fig09_efficiency.png: the efficiency scalar F per generation (Fig. 3, 9),
  drawn as F - F* on a log scale, F* = R* - 24 s being F at the exact optimum;
* fig04_error.png, fig07_errors.png: the error per generation (Fig. 4, 7);
* fig05_joint_angles.png: the joint angles against time of the planned motion (Fig. 5);
* fig10_reward.png: the error with and without the reward for ``--runs`` seeds (Fig. 10);
* fig11_arm.png: the arm in 3-D at the start and at the goal, with the tool path (Fig. 11);
* fig12_profiles.png: not in the paper: position, velocity, acceleration and jerk of each
  joint against time, the paper's target planned under each motion profile (servo,
  trapezoidal, jerk-limited; ``PROFILE_LIMITS``) with independent and synchronized timing.

Matplotlib is an optional extra (``figures``), imported when the command runs; figures are drawn
with ``matplotlib.figure.Figure`` and its Agg canvas, so no display is needed.
"""
from __future__ import annotations

import argparse
from dataclasses import replace
import importlib.util
from pathlib import Path
import sys
from typing import TYPE_CHECKING

import numpy as np
from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.motion.motion_profile import MotionProfile, Profile, Timing
from trajplan_ros.motion.trajectory import motion_states
from trajplan_ros.planning import planner
from trajplan_ros.planning.planner import PlanResult
from trajplan_ros.search.goal import Goal, Mode
from trajplan_ros.search.objective import Objective
from trajplan_ros.tools.bench.cases import paper_case
from trajplan_ros.tools.bench.methods import METHODS
from trajplan_ros.tools.bench.runner import run


if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ['make_figures', 'add_parser', 'FIGURES']

#: File name -> size in inches (width, height), in the order they are written.
FIGURES: dict[str, tuple[float, float]] = {
    'fig03_efficiency.png': (6.4, 4.4), 'fig04_error.png': (6.4, 4.4),
    'fig05_joint_angles.png': (8.0, 5.6), 'fig07_errors.png': (6.4, 4.8),
    'fig09_efficiency.png': (6.4, 4.8), 'fig10_reward.png': (9.6, 4.4),
    'fig11_arm.png': (6.4, 6.4), 'fig12_profiles.png': (16.0, 9.0),
}
#: The limits of fig12_profiles.png: every joint at most 0.2 rad/s (the paper's omega),
#: 0.2 rad/s^2 and 1 rad/s^3.
PROFILE_LIMITS = {'max_acceleration': 0.2, 'max_jerk': 1.0}
DEFAULT_SEED = 1
DEFAULT_RUNS = 5
_ERROR_FLOOR = 1e-17       # m: an error of 0 is drawn here on the log axis
_EXCESS_FLOOR = 1e-9       # s: F - F* at or below this is drawn here
_LABELS = {'iepso': 'IEPSO (this package)', 'iepso-paper': 'IEPSO as published',
           'pso': 'PSO', 'spso': 'SPSO', 'ga': 'GA', 'de': 'DE'}
_STYLE = {'iepso': ('C0', '-'), 'iepso-paper': ('C0', '--'), 'pso': ('C1', '-'),
          'spso': ('C2', '-'), 'ga': ('C3', '-'), 'de': ('C4', '-')}


def _generations(plan: PlanResult) -> np.ndarray:
    return np.arange(1, plan.history_error.size + 1)


def _error_axes(ax: Axes, eps: float) -> None:
    ax.set_xscale('log')
    ax.set_yscale('log')
    ax.set_xlabel('generation (log scale)')
    ax.set_ylabel(f'position error (m); 0 drawn at {_ERROR_FLOOR:g}')
    ax.axhline(eps, color='grey', lw=0.8, ls=':', label=f'reward threshold eps = {eps * 1e6:g} um')
    ax.axhline(1e-6, color='black', lw=0.8, ls=':', label='success: 1 um')
    ax.grid(True, which='major', alpha=0.3)


def _excess_axes(ax: Axes, f_star: float) -> None:
    ax.set_xscale('log')
    ax.set_yscale('log')
    ax.set_xlabel('generation (log scale)')
    ax.set_ylabel(f'F - F* (s), F* = {f_star:.3f} s; {_EXCESS_FLOOR:g} or less drawn at '
                  f'{_EXCESS_FLOOR:g}')
    ax.grid(True, which='major', alpha=0.3)


def _outcome(plan: PlanResult) -> str:
    return f'R = {plan.motion_time_s:.3f} s, error {plan.position_error_m:.1e} m'


def _plot_errors(fig: Figure, plans: dict[str, PlanResult], eps: float, title: str) -> None:
    ax = fig.add_subplot()
    for name, plan in plans.items():
        colour, style = _STYLE[name]
        ax.plot(_generations(plan), np.maximum(plan.history_error, _ERROR_FLOOR), color=colour,
                ls=style, label=f'{_LABELS[name]}: {_outcome(plan)}')
    _error_axes(ax, eps)
    ax.set_title(title)
    ax.legend(fontsize='small', loc='best')


def _plot_excess(fig: Figure, plans: dict[str, PlanResult], f_star: float, title: str) -> None:
    ax = fig.add_subplot()
    for name, plan in plans.items():
        colour, style = _STYLE[name]
        excess = np.maximum(plan.history_efficiency - f_star, _EXCESS_FLOOR)
        ax.plot(_generations(plan), excess, color=colour, ls=style,
                label=f'{_LABELS[name]}: F = {plan.efficiency:.4g} s')
    _excess_axes(ax, f_star)
    ax.set_title(title)
    ax.legend(fontsize='small', loc='best')


def _plot_joints(fig: Figure, plans: dict[str, PlanResult], arm: ArmModel) -> None:
    axes = fig.subplots(2, 2, sharex=True).ravel()
    for name, plan in plans.items():
        colour, style = _STYLE[name]
        traj = plan.trajectory()
        t = np.linspace(0.0, traj.duration, 400)
        q = traj.at_time(t)[0]
        for j, ax in enumerate(axes):
            ax.plot(t, q[:, j], color=colour, ls=style,
                    label=f'{_LABELS[name]} ({traj.duration:.2f} s)')
    for j, ax in enumerate(axes):
        ax.set_title(f'joint {j + 1} ({arm.joint_names[j]})', fontsize='medium')
        ax.set_ylabel('angle (rad)')
        ax.grid(True, alpha=0.3)
    for ax in axes[2:]:
        ax.set_xlabel('time (s)')
    axes[0].legend(fontsize='small')
    fig.suptitle('Fig. 5: joint angles against time, every servo at '
                 f"{plans['iepso'].angular_velocity:g} rad/s")


def _plot_reward(fig: Figure, runs: dict[str, list[PlanResult]], eps: float) -> None:
    axes = fig.subplots(1, 2, sharex=True, sharey=True)
    for ax, name in zip(axes, ('iepso-paper', 'iepso')):
        for variant, colour, text in ((name, 'C0', 'with reward'),
                                      (f'{name}-noreward', 'C3', 'without reward')):
            for k, plan in enumerate(runs[variant]):
                ax.plot(_generations(plan), np.maximum(plan.history_error, _ERROR_FLOOR),
                        color=colour, lw=1.0, alpha=0.7, label=text if k == 0 else None)
        _error_axes(ax, eps)
        ax.set_title(f'{_LABELS[name]}, {len(runs[name])} seeds', fontsize='medium')
    axes[1].set_ylabel('')
    axes[0].legend(fontsize='small', loc='lower left')
    fig.suptitle('Fig. 10: error with and without the reward term')


def _plot_arm(fig: Figure, plans: dict[str, PlanResult], arm: ArmModel) -> None:
    ax = fig.add_subplot(projection='3d')
    start = plans['iepso'].start
    joints = arm.frames(start)[0, :, :3, 3]
    ax.plot(*joints.T, 'o-', color='grey', lw=3, label='start (q = 0)')
    for name, plan in plans.items():
        colour, style = _STYLE[name]
        traj = plan.trajectory()
        path = arm.tool(traj.at_time(np.linspace(0.0, traj.duration, 200))[0])[0]
        ax.plot(*path.T, color=colour, ls=style, lw=1.5, label=f'tool path, {_LABELS[name]}')
        if name == 'iepso':
            for q in traj.at_time(np.linspace(0.0, traj.duration, 6)[1:-1])[0]:
                ax.plot(*arm.frames(q)[0, :, :3, 3].T, '-', color=colour, lw=1, alpha=0.25)
            ax.plot(*arm.frames(plan.joint_goal)[0, :, :3, 3].T, 'o-', color=colour, lw=3,
                    label=f'goal pose, {_LABELS[name]}')
    ax.scatter(*plans['iepso'].goal, marker='*', s=150, color='red', label='target', zorder=5)
    half = arm.reach / 2                     # a cube that holds the upright arm
    ax.set_xlim(-half, half)
    ax.set_ylim(-half, half)
    ax.set_zlim(0.0, 2 * half)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel('x (m)')
    ax.set_ylabel('y (m)')
    ax.set_zlabel('z (m)')
    ax.view_init(elev=20, azim=-60)
    ax.legend(fontsize='small', loc='upper left')
    ax.set_title('Fig. 11: the arm at the start and at the goal, with the tool path')


def _plot_profiles(fig: Figure, arm: ArmModel, goal: np.ndarray, seed: int) -> None:
    quantities = (('position', 'rad'), ('velocity', 'rad/s'), ('acceleration', 'rad/s²'),
                  ('jerk', 'rad/s³'))
    columns = [(p, t) for p in Profile for t in Timing]
    axes = fig.subplots(len(quantities), len(columns), sharex='col', sharey='row')
    for c, (profile, timing) in enumerate(columns):
        motion = MotionProfile(profile, timing, **PROFILE_LIMITS)
        result = planner.plan(goal, arm=arm, seed=seed, motion=motion)
        law = motion.time_law(arm, result.angular_velocity)
        t = np.linspace(0.0, result.motion_time_s * 1.02, 600)
        states = motion_states(result.start, result.joint_goal, law, motion.timing, t)
        for row, values in enumerate(states):
            for j in range(arm.planned):
                axes[row, c].plot(t, values[:, j], lw=1.2, color=f'C{j}',
                                  label=arm.joint_names[j])
            axes[row, c].grid(True, alpha=0.3)
        axes[0, c].set_title(f'{profile.value}, {timing.value}\n'
                             f'R = {result.motion_time_s:.2f} s', fontsize='medium')
        axes[-1, c].set_xlabel('time (s)')
    for row, (name, unit) in enumerate(quantities):
        axes[row, 0].set_ylabel(f'{name} ({unit})')
    axes[0, 0].legend(fontsize='small')
    fig.suptitle("The paper's target planned under each motion profile: every joint at most "
                 f"0.2 rad/s, {PROFILE_LIMITS['max_acceleration']:g} rad/s², "
                 f"{PROFILE_LIMITS['max_jerk']:g} rad/s³ (servo: velocity steps)")


def make_figures(outdir: Path, *, seed: int = DEFAULT_SEED, runs: int = DEFAULT_RUNS,
                 dpi: int = 100) -> list[Path]:
    """Plan the paper's experiment and write ``FIGURES`` into ``outdir``; returns the paths."""
    from matplotlib.figure import Figure

    arm, mode = paper_arm(), Mode.FREE
    case = paper_case(arm, mode, seed)
    obj = Objective(arm, Goal(case.goal, mode=mode), case.start)
    eps = obj.shaping.eps
    f_star = float(obj(case.exact.joint_goal).efficiency[0])
    five = ('iepso', 'iepso-paper', 'pso', 'spso', 'ga', 'de')
    single = run([METHODS[n] for n in five], [case], arm, mode)
    plans = {n: single[n].plans[0] for n in five}
    pair = {n: plans[n] for n in ('iepso', 'iepso-paper')}
    variants = ('iepso-paper', 'iepso-paper-noreward', 'iepso', 'iepso-noreward')
    seeds = [replace(case, seed=seed + k) for k in range(runs)]
    repeated = run([METHODS[n] for n in variants], seeds, arm, mode)
    reward_runs = {n: repeated[n].plans for n in variants}
    title = {n: f"Fig. {n}: {text}\n(paper's target from q = 0, seed {seed})" for n, text in (
        (3, 'efficiency scalar'), (4, 'error to the target'), (7, 'errors of the five algorithms'),
        (9, 'efficiency scalar of the five algorithms'))}

    drawings = {
        'fig03_efficiency.png': lambda f: _plot_excess(f, pair, f_star, title[3]),
        'fig04_error.png': lambda f: _plot_errors(f, pair, eps, title[4]),
        'fig05_joint_angles.png': lambda f: _plot_joints(f, pair, arm),
        'fig07_errors.png': lambda f: _plot_errors(f, plans, eps, title[7]),
        'fig09_efficiency.png': lambda f: _plot_excess(f, plans, f_star, title[9]),
        'fig10_reward.png': lambda f: _plot_reward(f, reward_runs, eps),
        'fig11_arm.png': lambda f: _plot_arm(f, pair, arm),
        'fig12_profiles.png': lambda f: _plot_profiles(f, arm, case.goal, seed),
    }
    outdir.mkdir(parents=True, exist_ok=True)
    written = []
    for name, size in FIGURES.items():
        fig = Figure(figsize=size, dpi=dpi, layout='constrained')
        drawings[name](fig)
        path = outdir / name
        fig.savefig(path, dpi=dpi)
        written.append(path)
    return written


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add the ``figures`` subcommand to the ``trajplan`` command's subparsers."""
    p = sub.add_parser('figures',
                       help="draw the paper's figures (3, 4, 5, 7, 9, 10, 11) as PNG files",
                       description="Plan the paper's experiment and draw its figures as PNG files "
                                   "(needs matplotlib: the package's 'figures' extra).")
    p.add_argument('outdir', type=Path,
                   help='folder to write the PNG files into (created if missing)')
    p.add_argument('--seed', type=int, default=DEFAULT_SEED,
                   help=f'seed of the runs (default {DEFAULT_SEED})')
    p.add_argument('--runs', type=int, default=DEFAULT_RUNS,
                   help=f'seeds drawn in Fig. 10 (default {DEFAULT_RUNS})')
    p.add_argument('--dpi', type=int, default=100, help='pixels per inch (default 100)')
    p.set_defaults(run=_run)


def _run(args: argparse.Namespace) -> int:
    if importlib.util.find_spec('matplotlib') is None:
        print('trajplan figures: matplotlib is not installed (pip install matplotlib, or the '
              "package's 'figures' extra)", file=sys.stderr)
        return 1
    if args.runs < 1 or args.dpi < 10:
        raise ValueError('--runs must be at least 1 and --dpi at least 10')
    for path in make_figures(args.outdir, seed=args.seed, runs=args.runs, dpi=args.dpi):
        print(path)
    return 0
