# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The ``trajplan bench`` subcommand: IEPSO against the paper's comparison algorithms and peers.

Every method (``methods.METHODS``: the paper's five algorithms, with and without the reward,
IEPSO as published and without its curve search, scipy's differential evolution and pyswarms)
runs on the same goals, starts, seeds and objective F, in one run (``runner.run``), and the
report (``report``) prints the table, the failed plans and, on request, CSV files. Progress goes
to stderr as a tqdm bar unless ``--quiet``.

``--paper`` runs the paper's experiment instead (its target from q = 0, its settings) and lays it
out like Table 5 beside the printed values, with the with/without-reward comparison of Fig. 10.

``--urdf`` benchmarks a URDF chain instead (``chain_bench``): no exact minimum there, so a
multi-start SLSQP solve is the reference, and the rows are IEPSO, scipy DE, pyswarms and ikpy.

``--profile`` (with ``--timing``, ``--joint-limits``, ``--max-acceleration``, ``--max-jerk``)
plans and scores every method under that motion profile, the references too; a ``--baseline``
row plans the servo law (an older version may know no other), for its plan time only.
"""
from __future__ import annotations

import argparse
from dataclasses import replace
import importlib.util
import itertools
import sys
from typing import Sequence

from trajplan_ros.kinematics import ArmModel
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.planning.planner import prepare
from trajplan_ros.search.goal import Mode
from trajplan_ros.search.objective import DEFAULT_OMEGA
from trajplan_ros.tools.arguments import (add_arm_arguments, add_motion_arguments,
                                          add_tolerance_arguments, arm_from_arguments,
                                          motion_from_arguments, positive_count, TOLERANCES,
                                          UsageError)
from trajplan_ros.tools.bench.baseline import baseline_method
from trajplan_ros.tools.bench.cases import Case, draw_cases, DRAWS, paper_case
from trajplan_ros.tools.bench.chain_bench import (ChainCase, ChainResults, draw_chain_cases,
                                                  format_chain, ikpy_method, IndependentFk,
                                                  region_cases, run_chain, tolerance_region)
from trajplan_ros.tools.bench.methods import load, Method, METHODS
from trajplan_ros.tools.bench.report import (format_criteria, format_failures,
                                             format_goals_heading, format_paper,
                                             format_paper_heading, format_sameness, format_sets,
                                             format_summary, summarise, write_plans_csv,
                                             write_summary_csv)
from trajplan_ros.tools.bench.runner import Results, run

__all__ = ['add_parser']

DEFAULT_GOALS = 100
QUICK_GOALS = 8
#: The rows of a URDF chain's bench unless --algorithms says otherwise.
CHAIN_METHODS = ('iepso', 'scipy-de', 'pyswarms', 'ikpy')


def _method_names(text: str) -> list[str]:
    names = [n.strip() for n in text.split(',') if n.strip()]
    unknown = [n for n in names if n not in METHODS and n != 'ikpy']
    if unknown:
        raise argparse.ArgumentTypeError(
            f"unknown method {unknown[0]!r}; choose from {', '.join(METHODS)}, ikpy (--urdf)")
    return names


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add the ``bench`` subcommand to the ``trajplan`` command's subparsers."""
    legend = '\n'.join(f'  {m.name:<22}{m.description}' for m in METHODS.values())
    p = sub.add_parser(
        'bench', help='compare IEPSO with PSO, SPSO, GA, DE, scipy and pyswarms on random goals',
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description='Run every method on the same seeded random goals and starts with the same '
                    'objective F. Success: error <= 1 um and motion time within 0.1 % of the '
                    'exact minimum. Time per plan: wall time of the call.',
        epilog='methods:\n' + legend)
    p.add_argument('--paper', action='store_true',
                   help="the paper's experiment (its target from q = 0) laid out like Table 5, "
                        'and Fig. 10')
    p.add_argument('--runs', type=positive_count, default=1, metavar='N',
                   help='with --paper: repeat with seeds SEED..SEED+N-1 (default 1)')
    p.add_argument('--quick', action='store_true',
                   help=f'{QUICK_GOALS} goals (unless --goals is given)')
    p.add_argument('--goals', type=positive_count, metavar='N',
                   help=f'number of goals (default {DEFAULT_GOALS})')
    p.add_argument('--algorithms', type=_method_names, nargs='+', metavar='NAME',
                   help='methods to run, by name, comma or space separated (default: all)')
    p.add_argument('--mode', choices=[m.value for m in Mode], default=Mode.FREE.value)
    p.add_argument('--random-starts', action='store_true',
                   help='start from random in-limit configurations instead of q = 0')
    p.add_argument('--sets', type=positive_count, default=1, metavar='N',
                   help='N sets of goals with seeds SEED..SEED+N-1, reported set by set too '
                        '(default 1)')
    p.add_argument('--only', choices=DRAWS, default='all',
                   help='draw only goals whose exact optimum has a joint on a limit, or only '
                        'goals without a solution (success: reported not reached); default all')
    p.add_argument('--seed', type=int, default=0,
                   help='seed of the goals, starts and plans (default 0)')
    p.add_argument('--baseline', metavar='DIR',
                   help='add a row "baseline": IEPSO of another version of this package, from '
                        'its source tree DIR (e.g. git worktree add DIR 56ebf49, the numpy '
                        'core), on the same goals in the same run')
    p.add_argument('--csv', metavar='FILE', help='also write the table as CSV')
    p.add_argument('--plans-csv', metavar='FILE',
                   help='write every plan (goal, start, answer, score) as CSV')
    p.add_argument('--failures', type=int, default=10, metavar='N',
                   help='failed plans listed per method (default 10, -1 for all)')
    p.add_argument('--quiet', action='store_true', help='no progress on stderr')
    p.add_argument('--reference-starts', type=positive_count, default=24, metavar='N',
                   help='with --urdf: SLSQP starts of the reference per goal (default 24)')
    add_arm_arguments(p)
    add_motion_arguments(p)
    add_tolerance_arguments(p, several=True)
    p.set_defaults(run=_run)


def _chosen_methods(args: argparse.Namespace, arm: ArmModel) -> tuple[list[Method], list[str]]:
    """Return the chosen methods that can run here, and a note for each that cannot."""
    default = CHAIN_METHODS if args.urdf else tuple(METHODS)
    wanted = {n for group in args.algorithms for n in group} if args.algorithms else set(default)
    table = dict(METHODS)
    if args.urdf:
        table['ikpy'] = ikpy_method(args.urdf, arm)
    elif 'ikpy' in wanted:
        raise UsageError('ikpy needs --urdf (it reads the chain from the file)')
    chosen = [table[n] for n in table if n in wanted]
    if args.baseline:
        try:
            chosen.append(baseline_method(args.baseline))
        except ValueError as exc:
            raise UsageError(str(exc)) from None
    notes = [f'{m.name}: {m.requires} is not installed, skipped '
             f"(pip install {m.requires}, or the package's 'bench' extra)"
             for m in chosen if not m.available]
    methods = [m for m in chosen if m.available]
    if not methods:
        raise UsageError('none of the chosen methods can run here: ' + '; '.join(notes))
    return methods, notes


def _cases(args: argparse.Namespace, arm: ArmModel, mode: Mode) -> list[Case]:
    """Return the cases the options ask for, after printing the line that says what they are."""
    if args.paper:
        if (args.goals or args.quick or args.random_starts or args.only != 'all'
                or args.sets != 1):
            raise UsageError('--paper is one fixed target: use --runs, not --goals, --quick, '
                             '--random-starts, --only or --sets')
        first = paper_case(arm, mode, args.seed, args.motion)
        print(format_paper_heading(mode, args.seed, args.runs))
        return [replace(first, seed=args.seed + r) for r in range(args.runs)]
    if args.runs != 1:
        raise UsageError('--runs goes with --paper; on random goals use --goals')
    n = args.goals or (QUICK_GOALS if args.quick else DEFAULT_GOALS)
    try:
        cases = [case for seed in range(args.seed, args.seed + args.sets)
                 for case in draw_cases(arm, n, mode=mode, random_starts=args.random_starts,
                                        seed=seed, only=args.only, profile=args.motion)]
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    print(format_goals_heading(n, mode, args.random_starts, args.seed, args.only, args.sets)
          + _motion_note(args))
    return cases


def _motion_note(args: argparse.Namespace) -> str:
    """Return what the heading says of the motion profile: nothing for the servo law."""
    if args.motion == MotionProfile():
        return ''
    return f' Motion: {args.motion.describe()} profile.'


def _run_with_progress(methods: Sequence[Method], cases: Sequence[Case], arm: ArmModel,
                       mode: Mode, *, unit: str, args: argparse.Namespace
                       ) -> dict[str, Results]:
    """Run the benchmark with a tqdm progress bar on stderr, unless ``--quiet``."""
    if args.quiet:
        return run(methods, cases, arm, mode, profile=args.motion)
    if importlib.util.find_spec('tqdm') is None:
        print("bench: no progress bar without tqdm (pip install tqdm, or the package's 'bench' "
              'extra)', file=sys.stderr)
        return run(methods, cases, arm, mode, profile=args.motion)
    from tqdm import tqdm

    with tqdm(total=len(cases), desc='bench', unit=unit, file=sys.stderr) as bar:
        return run(methods, cases, arm, mode, step=bar.update, profile=args.motion)


def _report(args: argparse.Namespace, results: dict[str, Results], cases: Sequence[Case],
            arm: ArmModel, mode: Mode) -> None:
    """Print the tables and failures, and write the CSV files asked for."""
    if args.paper:
        print(format_paper(results, cases[0], arm, mode))
        print(f"\nOver all {len(cases)} run(s) on the paper's target:")
    rows = summarise(results)
    print(format_summary(rows))
    print()
    if args.sets > 1:
        print(format_sets(results, cases) + '\n')
    print(format_failures(results, cases, args.failures))
    if args.baseline:
        print(format_sameness(results))
    if args.csv:
        write_summary_csv(args.csv, rows)
    if args.plans_csv:
        write_plans_csv(args.plans_csv, results, cases)


def _run_chain(args: argparse.Namespace, arm: ArmModel, mode: Mode, methods: list[Method],
               notes: list[str]) -> int:
    """Benchmark a URDF chain (``chain_bench``)."""
    if args.paper or args.only != 'all' or args.sets != 1 or args.runs != 1:
        raise UsageError('--urdf draws its own goals: --paper, --only, --sets and --runs do not '
                         'apply')
    n = args.goals or (QUICK_GOALS if args.quick else DEFAULT_GOALS)
    starts = 'random in-limit starts' if args.random_starts else 'q = 0 (clipped into limits)'
    print(f'trajplan bench --urdf: {n} goals, {arm.n_joints}-joint chain {arm.base_link} -> '
          f'{arm.tip_link} ({", ".join(arm.joint_names)}), {mode.value} mode, {starts}, seed '
          f'{args.seed}; reference: best of {args.reference_starts} SLSQP starts per goal.'
          + _motion_note(args))
    fk = IndependentFk(args.urdf, arm)
    try:
        cases, dropped = draw_chain_cases(arm, n, mode=mode, random_starts=args.random_starts,
                                          seed=args.seed, starts=args.reference_starts,
                                          profile=args.motion)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    if dropped:
        print(f'{dropped} drawn goal(s) dropped: the reference found no '
              f"{'' if mode is Mode.FREE else mode.value + ' '}pose for them"
              f"{' (or they lie below the base)' if mode is Mode.APPROACH else ''}.")
    print("success = error <= 1 um by yourdfpy's FK (radial: axis within 1e-6 rad of the goal "
          'ray; approach, from above: within 1e-3 rad; pose: orientation within 1e-6 rad), or '
          'within the tolerances given, and motion time at most 0.1 % above the reference; '
          'time = wall time per plan.')
    for tolerances in _tolerance_sets(args):
        results = _chain_results(args, arm, mode, methods, fk, cases, tolerances)
        if args.baseline:
            print(format_sameness(results))
    for note in notes:
        print(note)
    return 0


def _tolerance_sets(args: argparse.Namespace) -> list[dict[str, float]]:
    """Return each combination of the tolerances given (one empty set: none given)."""
    given = [name for name in TOLERANCES if getattr(args, name)]
    return [dict(zip(given, values))
            for values in itertools.product(*(getattr(args, name) for name in given))]


def _chain_results(args: argparse.Namespace, arm: ArmModel, mode: Mode, methods: list[Method],
                   fk: IndependentFk, cases: list[ChainCase],
                   tolerances: dict[str, float]) -> dict[str, ChainResults]:
    """Run and print the chain's table for one set of tolerances (the reference inside them)."""
    if tolerances:
        region = tolerance_region(tolerances, mode)
        cases = region_cases(cases, arm, mode, region, args.reference_starts, args.motion)
        print(f'\ntolerances {tolerances}: the reference is the least time inside them '
              '(SLSQP from the exact reference, the start and as many random points).')
    print()
    if args.quiet or importlib.util.find_spec('tqdm') is None:
        results = run_chain(methods, cases, arm, mode, fk, profile=args.motion,
                            tolerances=tolerances)
    else:
        from tqdm import tqdm

        with tqdm(total=len(cases), desc='bench', unit='goal', file=sys.stderr) as bar:
            results = run_chain(methods, cases, arm, mode, fk, step=bar.update,
                                profile=args.motion, tolerances=tolerances)
    print(format_chain(results, cases))
    return results


def _run(args: argparse.Namespace) -> int:
    arm, mode = arm_from_arguments(args), Mode(args.mode)
    if mode is Mode.POSE and not args.urdf:
        raise UsageError('--mode pose is benchmarked on a URDF chain of six or more joints '
                         '(--urdf)')
    args.motion = motion_from_arguments(args)
    args.motion.time_law(arm, DEFAULT_OMEGA)    # a profile without the limits it needs: refused
    if any(getattr(args, name) for name in TOLERANCES) and not args.urdf:
        raise UsageError('tolerances are benchmarked on a URDF chain (--urdf): the exact '
                         "minimum of the paper's arm is for its goal itself")
    methods, notes = _chosen_methods(args, arm)
    prepare()                      # compile or load the kernels now, not in the first timed plan
    if args.urdf:
        load(methods)
        return _run_chain(args, arm, mode, methods, notes)
    load(methods)                  # import the peers now, not inside the first timed call
    cases = _cases(args, arm, mode)
    print(format_criteria() + '\n')
    results = _run_with_progress(methods, cases, arm, mode, unit='run' if args.paper else 'goal',
                                 args=args)
    _report(args, results, cases, arm, mode)
    for note in notes:
        print(note)
    return 0
