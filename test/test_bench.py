# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
``trajplan bench``: seeded goals, one objective for every method, honest tables and CSV files.

No test asserts on wall-clock speed; the sizes are tiny so the file runs in seconds.
"""
from __future__ import annotations

import csv
import importlib.util
import logging
import os
from pathlib import Path
import subprocess
import sys

import numpy as np
import pytest

from trajplan_ros.kinematics import paper_arm
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.planning.planner import plan
from trajplan_ros.search.goal import Goal, Mode
from trajplan_ros.search.objective import Objective
from trajplan_ros.tools.bench.cases import Case, draw_cases, paper_case, PAPER_TABLE5
from trajplan_ros.tools.bench.methods import METHODS, pyswarms_logging
from trajplan_ros.tools.bench.reference import exact_minimum
from trajplan_ros.tools.bench.report import format_failures, format_sameness, summarise
from trajplan_ros.tools.bench.runner import Results, run
from trajplan_ros.tools.cli import main

ARM = paper_arm()
#: Not pytest.importorskip: importing pyswarms here, unguarded, would write ./report.log.
NEEDS_PYSWARMS = pytest.mark.skipif(importlib.util.find_spec('pyswarms') is None,
                                    reason='pyswarms is not installed')
SUMMARY_HEADER = ['method', 'goals', 'success_rate', 'median_error_m', 'worst_error_m',
                  'median_gap', 'median_time_s', 'p99_time_s', 'time_ratio_to_iepso']
PLANS_HEADER = (['method', 'goal_index', 'seed', 'goal_x_m', 'goal_y_m', 'goal_z_m']
                + [f'start_q{i}_rad' for i in range(1, 6)] + [f'q{i}_rad' for i in range(1, 5)]
                + ['error_m', 'axis_error_rad', 'motion_time_s', 'exact_time_s', 'gap',
                   'efficiency', 'time_s', 'success'])


def _read_csv(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    with open(path, newline='', encoding='utf-8') as handle:
        rows = list(csv.reader(handle))
    return rows[0], [dict(zip(rows[0], r)) for r in rows[1:]]


def test_cases_are_seeded_reachable_and_do_not_depend_on_the_starts() -> None:
    upright = draw_cases(ARM, 4, mode=Mode.FREE, random_starts=False, seed=3)
    again = draw_cases(ARM, 4, mode=Mode.FREE, random_starts=False, seed=3)
    moving = draw_cases(ARM, 4, mode=Mode.FREE, random_starts=True, seed=3)
    other = draw_cases(ARM, 4, mode=Mode.FREE, random_starts=False, seed=4)
    for a, b, c, d in zip(upright, again, moving, other):
        assert np.array_equal(a.goal, b.goal) and a.seed == b.seed
        assert np.array_equal(a.goal, c.goal) and a.seed == c.seed
        assert not np.array_equal(a.goal, d.goal)
        assert np.array_equal(a.start, np.zeros(5))
        assert ARM.within_limits(c.start) and np.all(c.start != 0)
        for case in (a, c):
            assert case.exact_time == exact_minimum(ARM, case.goal, case.start).motion_time_s
            assert np.isfinite(case.exact_time) and case.exact_time > 0
    assert len({c.seed for c in upright}) == 4


def test_radial_cases_all_have_a_radial_solution() -> None:
    cases = draw_cases(ARM, 6, mode=Mode.RADIAL, random_starts=True, seed=0)
    assert len(cases) == 6
    for case in cases:
        assert np.isfinite(exact_minimum(ARM, case.goal, case.start, mode='radial').motion_time_s)
        exact = exact_minimum(ARM, case.goal, case.start, mode='radial')
        assert case.exact_time == exact.motion_time_s


def test_every_method_is_scored_on_the_same_objective() -> None:
    case = draw_cases(ARM, 1, mode=Mode.FREE, random_starts=True, seed=1)[0]
    results = run([METHODS['iepso'], METHODS['iepso-noreward']], [case], ARM, Mode.FREE)
    default_f = Objective(ARM, Goal(case.goal), case.start)
    for name in ('iepso', 'iepso-noreward'):
        r = results[name]
        p = r.plans[0]
        assert np.array_equal(r.x[0], p.joint_goal[:4])
        assert r.error[0] == pytest.approx(p.position_error_m, abs=1e-15)
        assert r.motion_time[0] == pytest.approx(p.motion_time_s, rel=1e-12)
        assert r.gap[0] == pytest.approx(p.motion_time_s / case.exact_time - 1, abs=1e-12)
        assert r.seconds[0] > 0
        # F is the default objective's (with reward) for every row, so rows are comparable
        assert r.efficiency[0] == default_f(r.x[0]).efficiency[0]
    same = plan(case.goal, case.start, seed=case.seed)
    assert results['iepso'].efficiency[0] == pytest.approx(same.efficiency, abs=1e-9)


def test_radial_random_starts_from_the_command_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(['bench', '--goals', '1', '--mode', 'radial', '--random-starts',
                 '--algorithms', 'iepso', '--quiet', '--seed', '4']) == 0
    out = capsys.readouterr().out
    assert '1 goal, radial mode, random in-limit starts, seed 4' in out
    assert '\niepso ' in out


def test_same_seed_same_answers() -> None:
    case = draw_cases(ARM, 1, mode=Mode.FREE, random_starts=False, seed=2)[0]
    names = ['iepso', 'scipy-de'] if importlib.util.find_spec('scipy') else ['iepso']
    steps: list[int] = []
    first = run([METHODS[n] for n in names], [case], ARM, Mode.FREE, step=lambda: steps.append(1))
    second = run([METHODS[n] for n in names], [case], ARM, Mode.FREE)
    for n in names:
        assert np.array_equal(first[n].x, second[n].x)
    assert steps == [1]                                              # one step per case


def _results(error: list[float], gap: list[float], axis: list[float] | None = None) -> Results:
    r = Results.empty(len(error), 4)
    r.error[:], r.gap[:] = error, gap
    r.axis_error[:] = 0.0 if axis is None else axis
    r.seconds[:] = np.arange(1, len(error) + 1) * 1e-3
    r.x[:] = 0.0
    return r


def test_success_needs_both_the_error_and_the_gap() -> None:
    r = _results([0.0, 1e-6, 1.1e-6, 0.0, 5e-7], [0.0, 1e-3, 0.0, 1.01e-3, -1e-6])
    assert r.success.tolist() == [True, True, False, False, True]
    (row,) = summarise({'iepso': r})
    assert row.success_rate == pytest.approx(0.6)
    assert row.worst_error_m == 1.1e-6 and row.median_error_m == 5e-7
    assert row.median_time_s == pytest.approx(3e-3) and row.time_ratio_to_iepso == 1.0
    assert row.p99_time_s == pytest.approx(np.percentile([1e-3, 2e-3, 3e-3, 4e-3, 5e-3], 99))
    (alone,) = summarise({'pso': r})
    assert np.isnan(alone.time_ratio_to_iepso)                       # no IEPSO row to compare with


def test_radial_success_needs_the_axis_on_the_goal_ray() -> None:
    r = _results([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], axis=[1e-6, 1.1e-6, np.pi])
    assert r.success.tolist() == [True, False, False]


def test_on_goals_without_a_solution_success_is_not_claiming_it() -> None:
    r = _results([1e-3, 0.0, 1e-3], [np.nan, np.nan, np.nan], axis=[0.0, 0.0, 0.0])
    r.claimed[:] = [False, False, True]             # the last plan says SUCCEEDED anyway
    assert r.success.tolist() == [True, False, False]


def test_failures_are_listed_with_goal_start_seed_error_and_gap() -> None:
    goals = np.array([[0.1, 0.2, 0.15], [0.2, 0.0, 0.1]])
    starts = np.array([np.full(5, 0.25), np.zeros(5)])
    cases = [Case(g, q, exact_minimum(ARM, g, q), seed)
             for g, q, seed in zip(goals, starts, (11, 12))]
    results = {'iepso': _results([0.0, 0.0], [0.0, 0.0]), 'ga': _results([3e-4, 0.0], [0.5, 0.2])}
    text = format_failures(results, cases, limit=-1)
    assert 'iepso' not in text
    assert 'failures of ga (2 of 2):' in text
    assert 'goal (+0.1000, +0.2000, +0.1500) m' in text and 'start (+0.250, +0.250' in text
    assert 'seed 11' in text and 'error 3.00e-04 m' in text and 'gap +50.000 %' in text
    assert 'seed 12' in text and 'gap +20.000 %' in text
    short = format_failures(results, cases, limit=1)
    assert 'seed 11' in short and 'seed 12' not in short and '... 1 more' in short
    assert format_failures({'iepso': results['iepso']}, cases, limit=10) == 'no failures'


def test_bench_quick_writes_the_table_and_csv_files(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    table, plans = tmp_path / 'table.csv', tmp_path / 'plans.csv'
    assert main(['bench', '--quick', '--goals', '2', '--seed', '5', '--csv', str(table),
                 '--plans-csv', str(plans)]) == 0
    out, err = capsys.readouterr()
    ran = [m.name for m in METHODS.values() if m.available]
    assert 'trajplan bench: 2 goals, free mode' in out and 'time / iepso' in out
    assert 'bench: 100%' in err and '2/2' in err                      # progress, on stderr
    for m in METHODS.values():
        assert (f'{m.name}: {m.requires} is not installed, skipped' in out) == (not m.available)

    header, rows = _read_csv(table)
    assert header == SUMMARY_HEADER
    assert [r['method'] for r in rows] == ran
    header, per_plan = _read_csv(plans)
    assert header == PLANS_HEADER
    assert len(per_plan) == 2 * len(ran)
    for r in rows:
        mine = [p for p in per_plan if p['method'] == r['method']]
        assert [p['goal_index'] for p in mine] == ['0', '1']
        ok = [float(p['error_m']) <= 1e-6 and float(p['gap']) <= 1e-3 for p in mine]
        assert [p['success'] == 'True' for p in mine] == ok
        assert int(r['goals']) == 2 and float(r['success_rate']) == pytest.approx(np.mean(ok))
        times = [float(p['time_s']) for p in mine]
        assert float(r['median_time_s']) == pytest.approx(np.median(times))
        assert float(r['worst_error_m']) == pytest.approx(max(float(p['error_m']) for p in mine))
        assert float(r['time_ratio_to_iepso']) > 0
        for p in mine:
            ratio = float(p['motion_time_s']) / float(p['exact_time_s'])
            assert float(p['gap']) == pytest.approx(ratio - 1)
    assert next(r for r in rows if r['method'] == 'iepso')['time_ratio_to_iepso'] == '1.0'
    # the same goals and seeds for every method
    goals = {(p['goal_index'], p['goal_x_m'], p['seed']) for p in per_plan}
    assert len(goals) == 2


def test_a_missing_peer_is_skipped_with_a_note(monkeypatch: pytest.MonkeyPatch,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, 'find_spec',
                        lambda name, *a: None if name == 'pyswarms' else real(name, *a))
    assert main(['bench', '--goals', '1', '--algorithms', 'iepso,pyswarms', '--quiet']) == 0
    out = capsys.readouterr().out
    assert 'pyswarms: pyswarms is not installed, skipped (pip install pyswarms' in out
    assert '\niepso ' in out and '\npyswarms ' not in out


@NEEDS_PYSWARMS
def test_pyswarms_is_seeded_and_leaves_logging_and_numpy_alone(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv('LOG_CFG', raising=False)
    handlers = list(logging.getLogger().handlers)
    level = logging.getLogger().level
    np.random.seed(123)
    state = np.random.get_state()[1].copy()
    case = paper_case(ARM, Mode.FREE, 7)
    a = METHODS['pyswarms'].solve(ARM, Mode.FREE, case.goal, case.start, case.seed,
                                  MotionProfile())
    b = METHODS['pyswarms'].solve(ARM, Mode.FREE, case.goal, case.start, case.seed,
                                  MotionProfile())
    assert np.array_equal(a.x, b.x) and a.x.shape == (4,)
    assert list(tmp_path.iterdir()) == []                              # no ./report.log
    assert logging.getLogger().handlers == handlers and logging.getLogger().level == level
    assert 'LOG_CFG' not in os.environ
    assert np.array_equal(np.random.get_state()[1], state)


#: In a fresh interpreter, so that pyswarms' import (which makes Reporters too) is covered: load
#: and run the pyswarms method, then make a Reporter without the guard, which must misbehave.
_FRESH_PYSWARMS = """
import logging, os, sys
from trajplan_ros.kinematics import paper_arm
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.search.goal import Mode
from trajplan_ros.tools.bench.cases import paper_case
from trajplan_ros.tools.bench.methods import load, METHODS
root = logging.getLogger()
before = (list(root.handlers), root.level)
assert 'pyswarms' not in sys.modules
load([METHODS['pyswarms']])
case = paper_case(paper_arm(), Mode.FREE, 7)
METHODS['pyswarms'].solve(paper_arm(), Mode.FREE, case.goal, case.start, case.seed,
                          MotionProfile())
print(before == (list(root.handlers), root.level), os.environ.get('LOG_CFG'), os.listdir())
from pyswarms.utils import Reporter
Reporter()
print(before == (list(root.handlers), root.level), os.listdir())
"""


@NEEDS_PYSWARMS
def test_pyswarms_import_and_run_write_nothing_in_a_fresh_process(tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k != 'LOG_CFG'}
    env['PYTHONPATH'] = str(Path(__file__).resolve().parents[1])     # this tree's package
    if env.get('NUMBA_CACHE_DIR'):                 # the kernels' cache, not in the new folder
        env['NUMBA_CACHE_DIR'] = os.path.abspath(env['NUMBA_CACHE_DIR'])
    done = subprocess.run([sys.executable, '-c', _FRESH_PYSWARMS], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300, check=True)
    guarded, unguarded = done.stdout.splitlines()
    assert guarded == 'True None []'
    assert unguarded == "False ['report.log']"            # what the guard keeps from happening


def test_pyswarms_logging_points_pyswarms_at_a_configuration_of_nothing(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv('LOG_CFG', 'mine.yaml')
    with pyswarms_logging():
        config = Path(os.environ['LOG_CFG'])
        assert config.parent != tmp_path
        assert config.read_text(encoding='utf-8').split() == ['version:', '1', 'incremental:',
                                                              'true']
    assert os.environ['LOG_CFG'] == 'mine.yaml' and not config.exists()
    monkeypatch.delenv('LOG_CFG')
    with pyswarms_logging():
        assert 'LOG_CFG' in os.environ
    assert 'LOG_CFG' not in os.environ
    assert list(tmp_path.iterdir()) == []


def test_paper_mode_lays_out_table5_and_fig10(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    table = tmp_path / 'paper.csv'
    assert main(['bench', '--paper', '--runs', '2', '--algorithms', 'iepso', 'iepso-noreward',
                 '--csv', str(table), '--quiet']) == 0
    out = capsys.readouterr().out
    assert 'Table 5 as printed' in out
    for name, (q, f, _) in PAPER_TABLE5.items():
        row = next(line for line in out.splitlines() if line.startswith(name + ' '))
        assert f'{q[0]:+.2f}' in row and f'{f:.4g}' in row
    exact = next(line for line in out.splitlines() if line.startswith('exact optimum'))
    assert '4.514' in exact and '-19.49' in exact
    assert 'With and without the reward (Fig. 10)' in out
    assert "Over all 2 run(s) on the paper's target" in out
    header, rows = _read_csv(table)
    assert header == SUMMARY_HEADER
    assert [(r['method'], r['goals']) for r in rows] == [('iepso', '2'), ('iepso-noreward', '2')]


def test_progress_bar_on_stderr_unless_quiet(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ['bench', '--goals', '2', '--algorithms', 'iepso', '--seed', '1']
    assert main(argv) == 0
    shown = capsys.readouterr()
    assert main([*argv, '--quiet']) == 0
    quiet = capsys.readouterr()
    assert quiet.err == ''
    bar = shown.err.replace('\r', '\n').split()                     # tqdm redraws with \r
    assert bar[0] == 'bench:' and ' 0/2 ' in shown.err and 'bench: 100%' in shown.err
    assert '2/2' in shown.err.replace('\r', '\n').splitlines()[-1]
    assert 'goal' in shown.err
    assert '%|' not in shown.out                                      # stdout: the report only
    assert shown.out.splitlines()[:3] == quiet.out.splitlines()[:3]


def test_without_tqdm_the_run_goes_on_without_a_bar(monkeypatch: pytest.MonkeyPatch,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, 'find_spec',
                        lambda name, *a: None if name == 'tqdm' else real(name, *a))
    assert main(['bench', '--goals', '1', '--algorithms', 'iepso']) == 0
    out, err = capsys.readouterr()
    assert 'no progress bar without tqdm (pip install tqdm' in err and '%|' not in err
    assert '\niepso ' in out


@pytest.mark.parametrize('argv', [['bench', '--paper', '--goals', '3'], ['bench', '--runs', '2'],
                                  ['bench', '--paper', '--random-starts']])
def test_contradictory_options_are_usage_errors(argv: list[str],
                                                capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    assert 'trajplan: error:' in capsys.readouterr().err


def test_unknown_method_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(['bench', '--algorithms', 'iepso,simplex'])
    assert exc.value.code == 2
    assert "unknown method 'simplex'" in capsys.readouterr().err


def test_a_baseline_version_plans_the_same_goals_in_its_own_process(capsys, tmp_path) -> None:
    # this source tree as the baseline: the same planner, so the same answers, timed by the child
    repo = Path(__file__).resolve().parents[1]
    argv = ['bench', '--algorithms', 'iepso', '--goals', '3', '--seed', '5', '--quiet',
            '--baseline', str(repo)]
    assert main(argv) == 0
    rows = {line.split()[0]: line.split() for line in capsys.readouterr().out.splitlines()
            if line.startswith(('iepso ', 'baseline '))}
    assert rows['baseline'][1:3] == rows['iepso'][1:3] == ['100.00', '%']
    assert main(argv[:-1] + [str(tmp_path)]) == 2
    assert 'no trajplan_ros package in that folder' in capsys.readouterr().err


def test_a_slowdown_past_five_percent_of_the_baseline_is_named() -> None:
    def results(seconds: float) -> Results:
        out = Results.empty(3, 2)
        out.x[:], out.motion_time[:], out.seconds[:] = 0.0, 1.0, seconds
        return out

    within = format_sameness({'iepso': results(0.0104), 'baseline': results(0.0100)})
    assert within.splitlines()[0].startswith('baseline: the same joint goals bit for bit on 3 ')
    assert within.splitlines()[1] == ('baseline: median plan time 10.40 ms against the '
                                      "baseline's 10.00 ms (+4.0 %): not slower than the "
                                      'baseline by more than 5%')
    slower = format_sameness({'iepso': results(0.0106), 'baseline': results(0.0100)})
    assert slower.endswith('(+6.0 %): SLOWER than the baseline by more than 5%')
