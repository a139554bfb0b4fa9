"""
The ``trajplan bench`` subcommand: IEPSO against the paper's comparison algorithms and the peers
a Python user would pick instead, on the same goals, starts, seeds and objective F, in one run.

Methods (``METHODS``): the five algorithms of the paper through ``plan`` (IEPSO, PSO, SPSO, GA,
DE), each with the default rewards-and-punishment term and with ``RewardPunishment(reward=False)``
(suffix ``-noreward``, Fig. 10); IEPSO as published (``iepso-paper``: one swarm of 40, no
polish); IEPSO without its curve search (``iepso-nocurve``, an ablation); and scipy's
``differential_evolution`` (vectorised, polished, scipy's other defaults) and pyswarms'
``GlobalBestPSO`` (40 particles, 1000 iterations) minimising the same ``Objective``.

Goals are tool positions of seeded random in-limit configurations (in radial mode only those
with a radial solution); starts are q = 0 or random in-limit configurations. A plan succeeds when
its constraint error is at most 1 um and its motion time is within 0.1 % of the exact minimum
(``reference.exact_minimum``). Time per plan is the wall time of the ``plan`` (or peer) call,
including the construction of the objective, measured with ``time.perf_counter``; the methods take
turns goal by goal, so a busy machine slows them alike.

``--paper`` runs the paper's experiment instead (its target from q = 0, its settings) and lays it
out like Table 5 beside the printed values, with the with/without-reward comparison of Fig. 10.
"""
from __future__ import annotations

import argparse
import csv
import importlib.util
import sys
import time
from dataclasses import dataclass, replace
from functools import partial
from typing import Callable, ContextManager, Sequence, TextIO
from unittest import mock

import numpy as np

from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.tools.arguments import UsageError, positive_count
from trajplan_ros.planning.fuzzy import RewardPunishment
from trajplan_ros.planning.objective import DEFAULT_OMEGA, Mode, Objective
from trajplan_ros.planning.paper_experiment import PAPER_TABLE5, PAPER_TARGET
from trajplan_ros.planning.planner import ALGORITHMS, PlanResult, plan
from trajplan_ros.planning.reference import ExactOptimum, exact_minimum

__all__ = ['METHODS', 'Method', 'Answer', 'Case', 'Results', 'PAPER_TARGET', 'PAPER_TABLE5',
           'draw_cases', 'paper_case', 'run', 'summarise', 'add_parser']

#: Success: constraint error at most this (m) ...
SUCCESS_ERROR = 1e-6
#: ... and motion time at most this fraction above the exact minimum.
SUCCESS_GAP = 1e-3
DEFAULT_GOALS = 100
QUICK_GOALS = 8
#: Swarm size and iteration cap of the paper (Table 4), also given to pyswarms.
PARTICLES, ITERATIONS = 40, 1000
#: Constriction coefficients of Clerc and Kennedy (2002) for pyswarms.
PYSWARMS_OPTIONS = {'c1': 1.49618, 'c2': 1.49618, 'w': 0.7298}
_NO_REWARD = RewardPunishment(reward=False)


@dataclass(frozen=True)
class Answer:
    """A method's joint goal for the planned joints (rad), with the plan when ``plan`` made it."""

    x: np.ndarray
    plan: PlanResult | None = None


Solver = Callable[[ArmModel, Mode, np.ndarray, np.ndarray, int], Answer]


@dataclass(frozen=True)
class Method:
    """A row of the benchmark: ``solve(arm, mode, goal, start, seed)``; ``requires`` a module."""

    name: str
    description: str
    solve: Solver
    requires: str | None = None

    @property
    def available(self) -> bool:
        return self.requires is None or importlib.util.find_spec(self.requires) is not None


def _core(algorithm: str, shaping: RewardPunishment | None, options: dict | None,
          arm: ArmModel, mode: Mode, goal: np.ndarray, start: np.ndarray, seed: int) -> Answer:
    result = plan(goal, start, arm=arm, mode=mode, algorithm=algorithm, seed=seed,
                  shaping=shaping, options=options)
    if result.joint_goal is None:
        raise ValueError(f'{algorithm} rejected goal {goal.tolist()}: {result.message}')
    return Answer(result.joint_goal[: arm.planned], result)


def _scipy_de(arm: ArmModel, mode: Mode, goal: np.ndarray, start: np.ndarray, seed: int) -> Answer:
    from scipy.optimize import differential_evolution

    obj = Objective(arm, goal, start, mode=mode)
    # vectorized: x is (planned, S) for a generation and (planned, 1) while polishing
    found = differential_evolution(lambda x: obj(x.T).efficiency, list(zip(obj.lower, obj.upper)),
                                   vectorized=True, updating='deferred', polish=True,
                                   rng=np.random.default_rng(seed))
    return Answer(np.asarray(found.x))


def _quiet_logging() -> ContextManager:
    """
    Keep the process's logging as it is while pyswarms imports and builds its objects.

    Each of pyswarms' modules and objects calls ``logging.config.dictConfig``, which replaces the
    root logger's handlers and opens ./report.log in the working directory.
    """
    return mock.patch('logging.config.dictConfig')


def _pyswarms(arm: ArmModel, mode: Mode, goal: np.ndarray, start: np.ndarray, seed: int) -> Answer:
    obj = Objective(arm, goal, start, mode=mode)
    state = np.random.get_state()             # pyswarms draws from numpy's global generator
    np.random.seed(seed)
    try:
        with _quiet_logging():
            from pyswarms.single import GlobalBestPSO

            swarm = GlobalBestPSO(n_particles=PARTICLES, dimensions=obj.lower.size,
                                  options=PYSWARMS_OPTIONS, bounds=(obj.lower, obj.upper))
        _, x = swarm.optimize(lambda x: obj(x).efficiency, iters=ITERATIONS, verbose=False)
    finally:
        np.random.set_state(state)
    return Answer(np.asarray(x, dtype=float))


def _methods() -> dict[str, Method]:
    rows = []
    for algorithm in ALGORITHMS:
        label = algorithm.upper()
        what = ('this package: several swarms and a memetic polish' if algorithm == 'iepso'
                else "the paper's comparison")
        rows.append(Method(algorithm, f'{label} ({what}), rewards and punishment',
                           partial(_core, algorithm, None, None)))
        rows.append(Method(f'{algorithm}-noreward', f'{label} without the reward (Fig. 10)',
                           partial(_core, algorithm, _NO_REWARD, None)))
        if algorithm == 'iepso':
            paper = {'polish': False, 'swarms': 1}
            rows.append(Method('iepso-paper', 'IEPSO as published: one swarm of 40, no polish',
                               partial(_core, algorithm, None, paper)))
            rows.append(Method('iepso-paper-noreward', 'IEPSO as published, without the reward',
                               partial(_core, algorithm, _NO_REWARD, paper)))
            rows.append(Method('iepso-nocurve', 'IEPSO without the curve search (an ablation)',
                               partial(_core, algorithm, None, {'curve_search': 0})))
    rows.append(Method('scipy-de', 'scipy.optimize.differential_evolution (vectorized, polish)',
                       _scipy_de, 'scipy'))
    rows.append(Method('pyswarms', f'pyswarms GlobalBestPSO ({PARTICLES} particles, '
                       f'{ITERATIONS} iterations)', _pyswarms, 'pyswarms'))
    return {m.name: m for m in rows}


#: Every benchmark row by name, in table order.
METHODS: dict[str, Method] = _methods()


@dataclass(frozen=True)
class Case:
    """One benchmark goal: where to go, from where, the exact optimum and the plans' seed."""

    goal: np.ndarray
    start: np.ndarray
    exact: ExactOptimum
    seed: int

    @property
    def exact_time(self) -> float:
        return self.exact.motion_time_s


def draw_cases(arm: ArmModel, n: int, *, mode: Mode, random_starts: bool, seed: int) -> list[Case]:
    """
    ``n`` goals from seeded random in-limit configurations (rejecting goals without a solution).

    Each draw takes two configurations, the goal's and the start's, whether or not the start is
    used, so the goals do not depend on ``random_starts``.
    """
    rng = np.random.default_rng(seed)
    cases: list[Case] = []
    for _ in range(100 * n):
        if len(cases) == n:
            break
        q = arm.lower + (arm.upper - arm.lower) * rng.random((2, arm.n_joints))
        goal = arm.tool(q[:1])[0][0]
        start = q[1] if random_starts else np.zeros(arm.n_joints)
        plan_seed = int(rng.integers(2 ** 31))
        exact = exact_minimum(arm, goal, start, mode=mode.value)
        if np.isfinite(exact.motion_time_s):
            cases.append(Case(goal, start, exact, plan_seed))
    if len(cases) < n:
        raise ValueError(f'found only {len(cases)} of {n} goals with a {mode.value} solution')
    return cases


def paper_case(arm: ArmModel, mode: Mode, seed: int) -> Case:
    """The paper's experiment: its target from the upright pose q = 0."""
    start = np.zeros(arm.n_joints)
    return Case(PAPER_TARGET, start, exact_minimum(arm, PAPER_TARGET, start, mode=mode.value), seed)


@dataclass
class Results:
    """One method's outcome on every case (arrays indexed by case)."""

    x: np.ndarray              # (n, planned) joint goals, rad
    efficiency: np.ndarray     # F under the default objective (with reward), s
    error: np.ndarray          # constraint error, m
    motion_time: np.ndarray    # R, s
    gap: np.ndarray            # R / exact minimum - 1
    seconds: np.ndarray        # wall time per plan, s
    plans: list[PlanResult | None]

    @classmethod
    def empty(cls, n: int, planned: int) -> Results:
        return cls(np.full((n, planned), np.nan), *(np.full(n, np.nan) for _ in range(5)), [None] * n)

    @property
    def success(self) -> np.ndarray:
        return (self.error <= SUCCESS_ERROR) & (self.gap <= SUCCESS_GAP)


class Progress:
    """Progress on a stream: a redrawn bar on a terminal, a line every 10 % otherwise."""

    def __init__(self, total: int, stream: TextIO | None, unit: str = 'goals') -> None:
        self.total, self.stream, self.unit = total, stream, unit
        self.done, self.clock = 0, time.perf_counter()
        self.tty = stream is not None and stream.isatty()

    def step(self) -> None:
        self.done += 1
        if self.stream is None:
            return
        elapsed = time.perf_counter() - self.clock
        left = elapsed / self.done * (self.total - self.done)
        text = f'bench: {self.done}/{self.total} {self.unit}, {elapsed:.0f} s, about {left:.0f} s left'
        if self.tty:
            filled = 30 * self.done // self.total
            end = '\n' if self.done == self.total else ''
            self.stream.write(f"\r[{'#' * filled}{'.' * (30 - filled)}] {text}   {end}")
        elif 10 * self.done // self.total > 10 * (self.done - 1) // self.total:
            self.stream.write(text + '\n')
        self.stream.flush()


def run(methods: Sequence[Method], cases: Sequence[Case], arm: ArmModel, mode: Mode,
        progress: Progress | None = None) -> dict[str, Results]:
    """Every method on every case, taking turns goal by goal; answers scored on the same F."""
    out = {m.name: Results.empty(len(cases), arm.planned) for m in methods}
    for k, case in enumerate(cases):
        obj = Objective(arm, case.goal, case.start, mode=mode)
        for method in methods:
            clock = time.perf_counter()
            answer = method.solve(arm, mode, case.goal, case.start, case.seed)
            seconds = time.perf_counter() - clock
            ev = obj(answer.x)
            res = out[method.name]
            res.x[k], res.seconds[k], res.plans[k] = answer.x, seconds, answer.plan
            res.efficiency[k], res.error[k] = ev.efficiency[0], ev.error[0]
            res.motion_time[k] = ev.motion_time[0]
            res.gap[k] = ev.motion_time[0] / case.exact_time - 1.0
        if progress is not None:
            progress.step()
    return out


@dataclass(frozen=True)
class Summary:
    """A row of the benchmark table."""

    method: str
    goals: int
    success_rate: float
    median_error_m: float
    worst_error_m: float
    median_gap: float
    median_time_s: float
    p99_time_s: float
    time_ratio_to_iepso: float


def summarise(results: dict[str, Results]) -> list[Summary]:
    """Table rows; the time ratio is each median time over IEPSO's (NaN without an IEPSO row)."""
    reference = float(np.median(results['iepso'].seconds)) if 'iepso' in results else np.nan
    return [Summary(name, r.error.size, float(r.success.mean()), float(np.median(r.error)),
                    float(r.error.max()), float(np.median(r.gap)), float(np.median(r.seconds)),
                    float(np.percentile(r.seconds, 99)), float(np.median(r.seconds)) / reference)
            for name, r in results.items()]


def _table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """Plain text table: first column left-aligned, the others right-aligned."""
    widths = [max(len(c) for c in col) for col in zip(headers, *rows)]
    lines = []
    for row in (headers, *rows):
        cells = [row[0].ljust(widths[0])] + [c.rjust(w) for c, w in zip(row[1:], widths[1:])]
        lines.append('  '.join(cells).rstrip())
    lines.insert(1, '  '.join('-' * w for w in widths))
    return '\n'.join(lines)


def _vector(values: np.ndarray, digits: int = 4) -> str:
    return '(' + ', '.join(f'{v:+.{digits}f}' for v in values) + ')'


def _percent(fraction: float, digits: int) -> str:
    """A signed percentage that never prints as -0."""
    return f'{round(100 * fraction, digits) + 0.0:+.{digits}f} %'


def _ratio(value: float) -> str:
    return '-' if not np.isfinite(value) else f'{value:.1f}x'


def format_summary(rows: Sequence[Summary]) -> str:
    headers = ('method', 'success', 'median error (m)', 'worst error (m)', 'median gap',
               'median time (ms)', 'p99 time (ms)', 'time / iepso')
    body = [(s.method, f'{100 * s.success_rate:.1f} %', f'{s.median_error_m:.1e}',
             f'{s.worst_error_m:.1e}', _percent(s.median_gap, 3), f'{1e3 * s.median_time_s:.1f}',
             f'{1e3 * s.p99_time_s:.1f}', _ratio(s.time_ratio_to_iepso)) for s in rows]
    return _table(headers, body)


def format_failures(results: dict[str, Results], cases: Sequence[Case], limit: int) -> str:
    """Each method's failed plans: goal, start, seed, error and gap (``limit`` < 0: all)."""
    lines = []
    for name, r in results.items():
        failed = np.flatnonzero(~r.success)
        if not failed.size:
            continue
        lines.append(f'failures of {name} ({failed.size} of {r.error.size}):')
        shown = failed if limit < 0 else failed[:limit]
        for k in shown:
            case = cases[k]
            lines.append(f'  goal {_vector(case.goal)} m  start {_vector(case.start, 3)} rad  '
                         f'seed {case.seed}  error {r.error[k]:.2e} m  gap {_percent(r.gap[k], 3)}')
        if shown.size < failed.size:
            lines.append(f'  ... {failed.size - shown.size} more (--failures -1 lists all, '
                         '--plans-csv FILE writes every plan)')
    return '\n'.join(lines) if lines else 'no failures'


def write_summary_csv(path: str, rows: Sequence[Summary]) -> None:
    fields = list(Summary.__dataclass_fields__)
    with open(path, 'w', newline='', encoding='utf-8') as handle:
        writer = csv.writer(handle)
        writer.writerow(fields)
        writer.writerows([getattr(s, f) for f in fields] for s in rows)


def write_plans_csv(path: str, results: dict[str, Results], cases: Sequence[Case]) -> None:
    """One row per plan: the case, the joint goal and how it scored."""
    n_joints, planned = cases[0].start.size, next(iter(results.values())).x.shape[1]
    header = (['method', 'goal_index', 'seed', 'goal_x_m', 'goal_y_m', 'goal_z_m']
              + [f'start_q{i + 1}_rad' for i in range(n_joints)]
              + [f'q{i + 1}_rad' for i in range(planned)]
              + ['error_m', 'motion_time_s', 'exact_time_s', 'gap', 'efficiency', 'time_s', 'success'])
    with open(path, 'w', newline='', encoding='utf-8') as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for name, r in results.items():
            for k, case in enumerate(cases):
                writer.writerow([name, k, case.seed, *case.goal, *case.start, *r.x[k], r.error[k],
                                 r.motion_time[k], case.exact_time, r.gap[k], r.efficiency[k],
                                 r.seconds[k], bool(r.success[k])])


def _first_below(history: np.ndarray, level: float) -> str:
    hits = np.flatnonzero(history <= level)
    return str(hits[0] + 1) if hits.size else 'never'


def format_paper(results: dict[str, Results], case: Case, arm: ArmModel, mode: Mode) -> str:
    """Table 5 as printed, the same experiment here, and the with/without-reward comparison."""
    headers = ('algorithm', *(f'q{i + 1}' for i in range(arm.planned)), 'F', 'error (mm)', 'R (s)')
    printed = [(name, *(f'{v:+.2f}' for v in q), f'{f:.4g}', f'{err:.3g}',
                f'{np.max(np.abs(q)) / DEFAULT_OMEGA:.3f}')
               for name, (q, f, err) in PAPER_TABLE5.items()]
    exact = case.exact.joint_goal
    f_exact = float(Objective(arm, case.goal, case.start, mode=mode)(exact).efficiency[0])
    ours = [('exact optimum', *(f'{v:+.4f}' for v in exact), f'{f_exact:.4g}', '0',
             f'{case.exact_time:.3f}', '+0.00 %', '-')]
    ours += [(name, *(f'{v:+.4f}' for v in r.x[0]), f'{r.efficiency[0]:.4g}', f'{1e3 * r.error[0]:.3g}',
              f'{r.motion_time[0]:.3f}', _percent(r.gap[0], 2), f'{1e3 * r.seconds[0]:.1f}')
             for name, r in results.items()]
    eps = RewardPunishment().eps
    levels = (eps, SUCCESS_ERROR, 1e-12)
    reward_rows = []
    for name, r in results.items():
        if r.plans[0] is None or f'{name}-noreward' not in results:
            continue
        for label in (name, f'{name}-noreward'):
            res = results[label]
            history = res.plans[0].history_error
            reward_rows.append((label, *(_first_below(history, level) for level in levels),
                                str(history.size), f'{res.error[0]:.2e}', f'{res.motion_time[0]:.3f}'))
    parts = [
        'Table 5 as printed (Lv et al. 2019; error in mm; '
        f'R = max|q| / {DEFAULT_OMEGA:g} rad/s from the printed q):',
        _table(headers, printed),
        '',
        f'This run: the same target from q = 0, seed {case.seed} '
        '(F of the objective with reward, eq. 9):',
        _table((*headers, 'gap', 'time (ms)'), ours),
    ]
    if reward_rows:
        parts += ['', 'With and without the reward (Fig. 10): '
                      'first generation with the error at or below',
                  _table(('method', f'{eps * 1e6:g} um (eps)', '1 um', '1e-12 m', 'generations',
                          'final error (m)', 'R (s)'), reward_rows)]
    return '\n'.join(parts)


def _method_names(text: str) -> list[str]:
    names = [n.strip() for n in text.split(',') if n.strip()]
    unknown = [n for n in names if n not in METHODS]
    if unknown:
        raise argparse.ArgumentTypeError(
            f"unknown method {unknown[0]!r}; choose from {', '.join(METHODS)}")
    return names


def add_parser(sub: argparse._SubParsersAction) -> None:
    legend = '\n'.join(f'  {m.name:<22}{m.description}' for m in METHODS.values())
    p = sub.add_parser(
        'bench', help='compare IEPSO with PSO, SPSO, GA, DE, scipy and pyswarms on random goals',
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description='Run every method on the same seeded random goals and starts with the same '
                    'objective F. Success: error <= 1 um and motion time within 0.1 % of the exact '
                    'minimum. Time per plan: wall time of the call.',
        epilog='methods:\n' + legend)
    p.add_argument('--paper', action='store_true',
                   help="the paper's experiment (its target from q = 0) laid out like Table 5, "
                        'and Fig. 10')
    p.add_argument('--runs', type=positive_count, default=1, metavar='N',
                   help='with --paper: repeat with seeds SEED..SEED+N-1 (default 1)')
    p.add_argument('--quick', action='store_true', help=f'{QUICK_GOALS} goals (unless --goals is given)')
    p.add_argument('--goals', type=positive_count, metavar='N',
                   help=f'number of goals (default {DEFAULT_GOALS})')
    p.add_argument('--algorithms', type=_method_names, nargs='+', metavar='NAME',
                   help='methods to run, by name, comma or space separated (default: all)')
    p.add_argument('--mode', choices=[m.value for m in Mode], default=Mode.FREE.value)
    p.add_argument('--random-starts', action='store_true',
                   help='start from random in-limit configurations instead of q = 0')
    p.add_argument('--seed', type=int, default=0,
                   help='seed of the goals, starts and plans (default 0)')
    p.add_argument('--csv', metavar='FILE', help='also write the table as CSV')
    p.add_argument('--plans-csv', metavar='FILE',
                   help='write every plan (goal, start, answer, score) as CSV')
    p.add_argument('--failures', type=int, default=10, metavar='N',
                   help='failed plans listed per method (default 10, -1 for all)')
    p.add_argument('--quiet', action='store_true', help='no progress on stderr')
    p.set_defaults(run=_run)


def _run(args: argparse.Namespace) -> int:
    arm, mode = paper_arm(), Mode(args.mode)
    wanted = {n for group in args.algorithms for n in group} if args.algorithms else set(METHODS)
    chosen = [n for n in METHODS if n in wanted]
    methods = [METHODS[n] for n in chosen if METHODS[n].available]
    notes = [f'{METHODS[n].name}: {METHODS[n].requires} is not installed, skipped '
             f"(pip install {METHODS[n].requires}, or the package's 'bench' extra)"
             for n in chosen if not METHODS[n].available]
    if not methods:
        raise UsageError('none of the chosen methods can run here: ' + '; '.join(notes))
    with _quiet_logging():                 # import the peers now, not inside the first timed call
        for m in methods:
            if m.requires:
                importlib.import_module(m.requires)
    if args.paper:
        if args.goals or args.quick or args.random_starts:
            raise UsageError('--paper is one fixed target: use --runs, not --goals, --quick or '
                             '--random-starts')
        first = paper_case(arm, mode, args.seed)
        cases = [replace(first, seed=args.seed + r) for r in range(args.runs)]
        print(f"trajplan bench --paper: the paper's target {_vector(PAPER_TARGET, 6)} m from q = 0, "
              f'{mode.value} mode, {args.runs} run(s) with seeds {args.seed}..{args.seed + args.runs - 1}.')
    else:
        if args.runs != 1:
            raise UsageError('--runs goes with --paper; on random goals use --goals')
        n = args.goals or (QUICK_GOALS if args.quick else DEFAULT_GOALS)
        cases = draw_cases(arm, n, mode=mode, random_starts=args.random_starts, seed=args.seed)
        starts = 'random in-limit starts' if args.random_starts else 'starts upright (q = 0)'
        print(f"trajplan bench: {n} goal{'s' * (n != 1)}, {mode.value} mode, {starts}, seed {args.seed}; "
              'every method gets the same goals, starts and seeds.')
    print(f'success = error <= {SUCCESS_ERROR:g} m and motion time within {100 * SUCCESS_GAP:g} % of '
          'the exact minimum; time = wall time per plan.\n')
    progress = Progress(len(cases), None if args.quiet else sys.stderr,
                        'runs' if args.paper else 'goals')
    results = run(methods, cases, arm, mode, progress)
    if args.paper:
        print(format_paper(results, cases[0], arm, mode))
        print(f"\nOver all {len(cases)} run(s) on the paper's target:")
    rows = summarise(results)
    print(format_summary(rows))
    print()
    print(format_failures(results, cases, args.failures))
    if args.csv:
        write_summary_csv(args.csv, rows)
    if args.plans_csv:
        write_plans_csv(args.plans_csv, results, cases)
    for note in notes:
        print(note)
    return 0
