# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The benchmark's report: the summary table, the failed plans, Table 5, and the CSV files.

Everything here turns results into text or CSV; nothing plans.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from trajplan_ros.kinematics import ArmModel
from trajplan_ros.search.fuzzy import RewardPunishment
from trajplan_ros.search.goal import Goal, Mode
from trajplan_ros.search.objective import DEFAULT_OMEGA, Objective
from trajplan_ros.tools.bench.cases import Case, PAPER_TABLE5, PAPER_TARGET
from trajplan_ros.tools.bench.runner import (Results, SUCCESS_AXIS_ERROR, SUCCESS_ERROR,
                                             SUCCESS_GAP)

__all__ = ['Summary', 'summarise', 'format_criteria', 'format_failures', 'format_goals_heading',
           'format_paper', 'format_paper_heading', 'format_sets', 'format_summary',
           'format_sameness', 'format_table', 'write_plans_csv', 'write_summary_csv']


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
    """Return the table rows; the time ratio is each median time over IEPSO's (NaN without it)."""
    reference = float(np.median(results['iepso'].seconds)) if 'iepso' in results else np.nan
    return [Summary(name, r.error.size, float(r.success.mean()), float(np.median(r.error)),
                    float(r.error.max()), float(np.median(r.gap)), float(np.median(r.seconds)),
                    float(np.percentile(r.seconds, 99)), float(np.median(r.seconds)) / reference)
            for name, r in results.items()]


def format_table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """Lay out a plain text table: first column left-aligned, the others right-aligned."""
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
    """Format a signed percentage that never prints as -0."""
    return f'{round(100 * fraction, digits) + 0.0:+.{digits}f} %'


def _ratio(value: float) -> str:
    return '-' if not np.isfinite(value) else f'{value:.1f}x'


_KINDS = {'all': '', 'limit-optima': ' with the exact optimum on a joint limit',
          'no-solution': ' without a solution'}


def format_goals_heading(n: int, mode: Mode, random_starts: bool, seed: int,
                         only: str = 'all', sets: int = 1) -> str:
    """Return the first line of a run on random goals."""
    starts = 'random in-limit starts' if random_starts else 'starts upright (q = 0)'
    seeds = f'seed {seed}' if sets == 1 else f'{sets} sets, seeds {seed}..{seed + sets - 1}'
    each = ' each' if sets > 1 else ''
    return (f"trajplan bench: {n} goal{'s' * (n != 1)}{each}{_KINDS[only]}, {mode.value} mode, "
            f'{starts}, {seeds}; every method gets the same goals, starts and seeds.')


def format_sets(results: dict[str, Results], cases: Sequence[Case]) -> str:
    """Return each method's success set by set, and its worst set."""
    seeds = np.array([case.draw_seed for case in cases])
    lines = []
    for name, r in results.items():
        rates = {int(s): float(r.success[seeds == s].mean()) for s in np.unique(seeds)}
        worst = min(rates, key=rates.get)
        lines.append(f'{name} per set (seed: success): '
                     + ', '.join(f'{s}: {100 * v:.2f} %' for s, v in rates.items())
                     + f'; worst {100 * rates[worst]:.2f} % (seed {worst})')
    return '\n'.join(lines)


def format_paper_heading(mode: Mode, seed: int, runs: int) -> str:
    """Return the first line of a run on the paper's target."""
    return (f"trajplan bench --paper: the paper's target {_vector(PAPER_TARGET, 6)} m from "
            f'q = 0, {mode.value} mode, {runs} run(s) with seeds {seed}..{seed + runs - 1}.')


def format_criteria() -> str:
    """Return the line that says what success and time mean."""
    return (f'success = error <= {SUCCESS_ERROR:g} m (radial: axis within {SUCCESS_AXIS_ERROR:g} '
            f'rad of the goal ray) and motion time within {100 * SUCCESS_GAP:g} % of the exact '
            'minimum; on goals without a solution: reported not reached. '
            'time = wall time per plan.')


def format_summary(rows: Sequence[Summary]) -> str:
    """Lay out the summary rows as the benchmark table."""
    headers = ('method', 'success', 'median error (m)', 'worst error (m)', 'median gap',
               'median time (ms)', 'p99 time (ms)', 'time / iepso')
    body = [(s.method, f'{100 * s.success_rate:.2f} %', f'{s.median_error_m:.1e}',
             f'{s.worst_error_m:.1e}', _percent(s.median_gap, 3), f'{1e3 * s.median_time_s:.1f}',
             f'{1e3 * s.p99_time_s:.1f}', _ratio(s.time_ratio_to_iepso)) for s in rows]
    return format_table(headers, body)


def format_failures(results: dict[str, Results], cases: Sequence[Case], limit: int) -> str:
    """List each method's failed plans: goal, start, seed, error and gap (``limit`` < 0: all)."""
    lines = []
    for name, r in results.items():
        failed = np.flatnonzero(~r.success)
        if not failed.size:
            continue
        lines.append(f'failures of {name} ({failed.size} of {r.error.size}):')
        shown = failed if limit < 0 else failed[:limit]
        for k in shown:
            case = cases[k]
            status = '' if r.plans[k] is None else f'  {r.plans[k].status.value}'
            lines.append(f'  set {case.draw_seed}  goal {_vector(case.goal)} m  '
                         f'start {_vector(case.start, 3)} rad  seed {case.seed}  '
                         f'error {r.error[k]:.2e} m  '
                         f'axis {r.axis_error[k]:.2e} rad  gap {_percent(r.gap[k], 3)}{status}')
        if shown.size < failed.size:
            lines.append(f'  ... {failed.size - shown.size} more (--failures -1 lists all, '
                         '--plans-csv FILE writes every plan)')
    return '\n'.join(lines) if lines else 'no failures'


def _first_below(history: np.ndarray, level: float) -> str:
    hits = np.flatnonzero(history <= level)
    return str(hits[0] + 1) if hits.size else 'never'


def _run_rows(results: dict[str, Results], case: Case, arm: ArmModel,
              mode: Mode) -> list[tuple[str, ...]]:
    """Return the rows of this run on the paper's target, the exact optimum first."""
    exact = case.exact.joint_goal
    f_exact = float(Objective(arm, Goal(case.goal, mode=mode), case.start)(exact).efficiency[0])
    rows = [('exact optimum', *(f'{v:+.4f}' for v in exact), f'{f_exact:.4g}', '0',
             f'{case.exact_time:.3f}', '+0.00 %', '-')]
    rows += [(name, *(f'{v:+.4f}' for v in r.x[0]), f'{r.efficiency[0]:.4g}',
              f'{1e3 * r.error[0]:.3g}', f'{r.motion_time[0]:.3f}', _percent(r.gap[0], 2),
              f'{1e3 * r.seconds[0]:.1f}')
             for name, r in results.items()]
    return rows


def _reward_rows(results: dict[str, Results], levels: Sequence[float]) -> list[tuple[str, ...]]:
    """Return the first generation at each error level, for each method run with and without."""
    rows = []
    for name, r in results.items():
        if r.plans[0] is None or f'{name}-noreward' not in results:
            continue
        for label in (name, f'{name}-noreward'):
            res = results[label]
            history = res.plans[0].history_error
            rows.append((label, *(_first_below(history, level) for level in levels),
                         str(history.size), f'{res.error[0]:.2e}', f'{res.motion_time[0]:.3f}'))
    return rows


def format_paper(results: dict[str, Results], case: Case, arm: ArmModel, mode: Mode) -> str:
    """Lay out Table 5 as printed, the same experiment here, and the with/without reward."""
    headers = ('algorithm', *(f'q{i + 1}' for i in range(arm.planned)), 'F', 'error (mm)',
               'R (s)')
    printed = [(name, *(f'{v:+.2f}' for v in q), f'{f:.4g}', f'{err:.3g}',
                f'{np.max(np.abs(q)) / DEFAULT_OMEGA:.3f}')
               for name, (q, f, err) in PAPER_TABLE5.items()]
    eps = RewardPunishment().eps
    reward_rows = _reward_rows(results, (eps, SUCCESS_ERROR, 1e-12))
    parts = [
        'Table 5 as printed (Lv et al. 2019; error in mm; '
        f'R = max|q| / {DEFAULT_OMEGA:g} rad/s from the printed q):',
        format_table(headers, printed),
        '',
        f'This run: the same target from q = 0, seed {case.seed} '
        '(F of the objective with reward, eq. 9):',
        format_table((*headers, 'gap', 'time (ms)'), _run_rows(results, case, arm, mode)),
    ]
    if reward_rows:
        parts += ['', 'With and without the reward (Fig. 10): '
                      'first generation with the error at or below',
                  format_table(('method', f'{eps * 1e6:g} um (eps)', '1 um', '1e-12 m',
                                'generations', 'final error (m)', 'R (s)'), reward_rows)]
    return '\n'.join(parts)


def write_summary_csv(path: str, rows: Sequence[Summary]) -> None:
    """Write the table as CSV, one column per ``Summary`` field."""
    fields = list(Summary.__dataclass_fields__)
    with open(path, 'w', newline='', encoding='utf-8') as handle:
        writer = csv.writer(handle)
        writer.writerow(fields)
        writer.writerows([getattr(s, f) for f in fields] for s in rows)


def write_plans_csv(path: str, results: dict[str, Results], cases: Sequence[Case]) -> None:
    """Write one row per plan: the case, the joint goal and how it scored."""
    n_joints, planned = cases[0].start.size, next(iter(results.values())).x.shape[1]
    header = (['method', 'goal_index', 'seed', 'goal_x_m', 'goal_y_m', 'goal_z_m']
              + [f'start_q{i + 1}_rad' for i in range(n_joints)]
              + [f'q{i + 1}_rad' for i in range(planned)]
              + ['error_m', 'axis_error_rad', 'motion_time_s', 'exact_time_s', 'gap', 'efficiency',
                 'time_s',
                 'success'])
    with open(path, 'w', newline='', encoding='utf-8') as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for name, r in results.items():
            for k, case in enumerate(cases):
                writer.writerow([name, k, case.seed, *case.goal, *case.start, *r.x[k], r.error[k],
                                 r.axis_error[k], r.motion_time[k], case.exact_time, r.gap[k],
                                 r.efficiency[k],
                                 r.seconds[k], bool(r.success[k])])


#: A median plan time more than this fraction above the baseline's is named a slowdown.
SLOWDOWN = 0.05


def format_sameness(results: dict) -> str:
    """
    Return how the baseline's plans compare with IEPSO's, goal by goal, and their speed.

    The joint goals bit for bit, and the largest difference of a joint angle and (where the
    results have it) of the motion time: a change that should change no plan (a move of code,
    a rename) must show all, 0 and 0. Then both median plan times: more than ``SLOWDOWN``
    slower than the baseline is named so.
    """
    if 'iepso' not in results or 'baseline' not in results:
        return 'baseline: compared with iepso only (add iepso to --algorithms)'
    ours, theirs = results['iepso'], results['baseline']
    mine, other = (getattr(ours, 'x', None), getattr(theirs, 'x', None))
    if mine is None:
        mine, other = ours.q, theirs.q
    same = np.all(mine == other, axis=1)
    angle = float(np.nanmax(np.abs(mine - other), initial=0.0))
    line = (f'baseline: the same joint goals bit for bit on {int(same.sum())} of {len(same)} '
            f'goals; largest joint difference {angle:.3g} rad')
    if hasattr(ours, 'motion_time'):
        difference = np.abs(ours.motion_time - theirs.motion_time)
        line += f', largest motion time difference {float(np.nanmax(difference)):.3g} s'
    mine_s, theirs_s = float(np.median(ours.seconds)), float(np.median(theirs.seconds))
    change = mine_s / theirs_s - 1.0
    verdict = (f'SLOWER than the baseline by more than {SLOWDOWN:.0%}' if change > SLOWDOWN
               else f'not slower than the baseline by more than {SLOWDOWN:.0%}')
    return (f"{line}\nbaseline: median plan time {1e3 * mine_s:.2f} ms against the baseline's "
            f'{1e3 * theirs_s:.2f} ms ({_percent(change, 1)}): {verdict}')
