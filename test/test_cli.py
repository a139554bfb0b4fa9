# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The trajplan command: one goal, a goals file, bad input."""
import json
import re
import subprocess
import sys

import pytest
from trajplan_ros.planning import planner
from trajplan_ros.tools.bench.cases import PUBLISHED
from trajplan_ros.tools.cli import build_parser, main


TARGET = ['0.151171', '0.19162', '0.172124']


def test_plan_one_goal_human_readable(capsys):
    assert main(['plan', *TARGET]) == 0
    out = capsys.readouterr().out
    assert 'succeeded' in out and 'joint goal [rad]' in out and '4.5143 s' in out


def test_plan_json_radial(capsys):
    assert main(['plan', *TARGET, '--mode', 'radial', '--json', '--seed', '3']) == 0
    record = json.loads(capsys.readouterr().out)
    assert record['success'] and record['mode'] == 'radial'
    assert record['motion_time_s'] == pytest.approx(6.691749, rel=1e-3)


def test_goals_file_keeps_order_and_reports_bad_lines(tmp_path, capsys):
    goals = tmp_path / 'goals.csv'
    goals.write_text('# x,y,z[,start]\n0.151171,0.19162,0.172124\n1,2\n0.2,abc,0.1\n'
                     '0.9,0.9,0.9\n0.2,0.1,0.15,0.1,0.2,0,0,0\n')
    assert main(['plan', '--goals', str(goals), '--json']) == 1
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r['line'] for r in lines] == [2, 3, 4, 5, 6]
    assert [r['success'] for r in lines] == [True, False, False, False, True]
    assert '3 field(s)' not in lines[1]['message'] and '2 field(s)' in lines[1]['message']
    assert 'not a number' in lines[2]['message']
    assert "beyond the arm's reach" in lines[3]['message']
    assert lines[4]['joint_goal'] is not None


def test_plan_past_max_planning_time_is_timed_out(monkeypatch, capsys):
    clock = iter(range(1000))                       # one second per reading, never the real one
    monkeypatch.setattr(planner, '_clock', lambda: float(next(clock)))
    # an out-of-reach goal: the search would go on for dozens of iterations
    assert main(['plan', '0.36', '0', '0.05', '--json', '--max-planning-time', '3']) == 1
    record = json.loads(capsys.readouterr().out)
    assert record['status'] == 'timed_out' and record['success'] is False
    assert record['iterations'] == 3 and record['joint_goal'] is not None
    assert record['message'].startswith('planning ran past max_planning_time 3 s; best position '
                                        'error ')


@pytest.mark.parametrize('argv, reason', [
    (['plan', '0.1', '0.2'], 'X Y Z'),
    (['plan', *TARGET, '--start', '0', '0', '0', '0', '0', '0'],
     'a start needs 5 joint angles (or the 4 planned ones), got 6'),
    (['plan', *TARGET, '--start', '0.1'],
     'a start needs 5 joint angles (or the 4 planned ones), got 1'),
    (['plan', '--goals', '/nonexistent/goals.csv'], 'cannot read'),
    (['plan', *TARGET, '--max-planning-time', '0'], 'max_planning_time'),
    (['plan', *TARGET, '--profile', 'trapezoidal'],
     'the trapezoidal profile needs an acceleration limit for joint joint1'),
    (['plan', *TARGET, '--profile', 'jerk_limited', '--max-acceleration', '1'],
     'needs a jerk limit for joint joint1'),
    (['plan', *TARGET, '--max-jerk', '-1'], 'max_jerk must be finite and positive, got -1.0'),
    (['plan', *TARGET, '--joint-limits', '/nonexistent/limits.yaml'], 'cannot read joint limits'),
])
def test_bad_arguments_exit_2_with_one_line(argv, reason, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert reason in err and '\n' not in err


def test_argparse_errors_exit_2():
    proc = subprocess.run([sys.executable, '-m', 'trajplan_ros.tools.cli', 'plan', '0.1', 'nan',
                           '0.1'],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and 'not a finite number' in proc.stderr


def test_csv_starts_are_strict_and_empty_fields_get_a_reason(tmp_path, capsys):
    goals = tmp_path / 'goals.csv'
    goals.write_text('0.1,0.1,0.1,0.0\n,,\n\n0.1,0.1,0.1,0.2,0.1,0.0,0.1\n'
                     '1e308,1e308,1e308\n', encoding='utf-8')
    assert main(['plan', '--goals', str(goals), '--json']) == 1
    captured = capsys.readouterr()
    lines = [json.loads(line) for line in captured.out.splitlines()]
    assert [r['line'] for r in lines] == [1, 2, 4, 5]              # the blank line 3: skipped
    assert lines[0]['status'] == 'rejected'
    assert 'a start needs 5 joint angles (or the 4 planned ones), got 1' in lines[0]['message']
    assert lines[1]['message'] == ('line 2: empty field(s) 1, 2, 3: expected '
                                   'x,y,z[,start angles]')
    assert lines[2]['success'] and lines[2]['joint_goal'][4] == 0.0    # held joint5 at 0
    assert lines[3]['status'] == 'rejected' and 'beyond the arm' in lines[3]['message']
    assert captured.err == ''                                          # no numpy warnings


def test_a_radial_goal_at_the_origin_is_refused_without_warnings(capsys):
    assert main(['plan', '0', '0', '0', '--mode', 'radial', '--json']) == 1
    captured = capsys.readouterr()
    record = json.loads(captured.out)
    assert record['status'] == 'rejected' and 'away from the base origin' in record['message']
    assert captured.err == ''


def test_plan_for_a_published_urdf_names_its_joints(tmp_path, capsys):
    so101 = PUBLISHED['so101']
    goals = tmp_path / 'goals.csv'
    goals.write_text('0.2,0.1,0.15\n0.2,0.1,0.15,0.1,0.2,0.3,0.1,0.0\n0.2,0.1,0.15,0.1,0.2\n')
    argv = ['plan', '--goals', str(goals), '--json', '--urdf', str(so101.urdf),
            '--base-link', so101.base_link, '--tip-link', so101.tip_link]
    assert main(argv) == 1
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert all(r['joint_names'] == ['shoulder_pan', 'shoulder_lift', 'elbow_flex',
                                    'wrist_flex', 'wrist_roll'] for r in lines)
    assert [r['success'] for r in lines] == [True, True, False]
    assert len(lines[0]['joint_goal']) == 5
    assert 'a start needs 5 joint angles, got 2' in lines[2]['message']


def test_planning_from_trajplan_urdf_output_matches_the_dh_model(tmp_path, capsys):
    urdf = tmp_path / 'paper_arm.urdf'
    assert main(['urdf', '-o', str(urdf)]) == 0
    for goal in (TARGET, ['0.12', '-0.1', '0.25'], ['-0.05', '0.15', '0.05']):
        capsys.readouterr()
        assert main(['plan', *goal, '--json']) == 0
        dh = json.loads(capsys.readouterr().out)
        assert main(['plan', *goal, '--json', '--urdf', str(urdf), '--tip-link', 'tool_link']) == 0
        chain = json.loads(capsys.readouterr().out)
        assert chain['joint_names'] == dh['joint_names']
        assert chain['motion_time_s'] == pytest.approx(dh['motion_time_s'], rel=1e-6)
        assert chain['joint_goal'][:4] == pytest.approx(dh['joint_goal'][:4], abs=1e-5)


@pytest.mark.parametrize('argv, reason', [
    (['--tip-link', 'x'], '--tip-link needs --urdf'),
    (['--urdf', '/no/such.urdf'], 'cannot read the URDF'),
    (['--urdf', '{so101}', '--tip-link', 'nowhere'], "unknown link 'nowhere'"),
])
def test_bad_arm_arguments_exit_2_with_one_line(argv, reason, capsys):
    argv = [a.replace('{so101}', str(PUBLISHED['so101'].urdf)) for a in argv]
    assert main(['plan', *TARGET, *argv]) == 2
    err = capsys.readouterr().err
    assert reason in err and err.count('\n') == 1


def subcommands() -> list[str]:
    """Return the names of ``trajplan``'s subcommands, from its parser."""
    parser = build_parser()
    return [name for action in parser._subparsers._group_actions
            for name in action.choices]


@pytest.mark.parametrize('command', [None, *subcommands()])
def test_every_help_works(command, capsys):
    with pytest.raises(SystemExit) as exited:
        main([command, '--help'] if command else ['--help'])
    assert exited.value.code == 0
    assert capsys.readouterr().out.startswith('usage: trajplan')


def test_angular_velocity_sets_the_servo_speed(capsys):
    assert main(['plan', *TARGET, '--json']) == 0
    slow = json.loads(capsys.readouterr().out)
    assert main(['plan', *TARGET, '--json', '--angular-velocity', '1.0']) == 0
    fast = json.loads(capsys.readouterr().out)
    assert fast['motion_time_s'] == pytest.approx(slow['motion_time_s'] * 0.2, rel=1e-9)
    assert main(['plan', *TARGET, '--angular-velocity', '0']) == 2
    assert 'angular_velocity must be finite and positive' in capsys.readouterr().err


def test_trajectory_is_the_message_as_published(capsys):
    assert main(['plan', *TARGET, '--json', '--trajectory', '--sample-period', '0.5']) == 0
    record = json.loads(capsys.readouterr().out)
    trajectory = record['trajectory']
    assert trajectory['joint_names'] == record['joint_names']
    points = trajectory['points']
    times = [p['time_from_start'] for p in points]
    assert times[0] > 0 and all(b > a for a, b in zip(times, times[1:]))
    assert times[-1] == pytest.approx(record['motion_time_s'], abs=1e-9)
    assert points[-1]['positions'] == record['joint_goal']
    assert all(p['velocities'] == [] and p['accelerations'] == [] for p in points)
    assert main(['plan', '1', '1', '1', '--json', '--trajectory']) == 1      # out of reach
    assert json.loads(capsys.readouterr().out)['trajectory'] is None
    assert main(['plan', *TARGET, '--trajectory']) == 2
    assert '--trajectory needs --json' in capsys.readouterr().err
    # a trajectory past the bound is not built: the plan stands, the message says why
    assert main(['plan', *TARGET, '--json', '--trajectory', '--sample-period', '1e-6']) == 0
    record = json.loads(capsys.readouterr().out)
    assert record['success'] and record['trajectory'] is None
    assert re.search(r'; no trajectory: it would need \d{7} points, more than '
                     r'--max-trajectory-points 10000$', record['message'])


def test_a_profile_plans_its_duration_and_publishes_its_derivatives(tmp_path, capsys):
    limits = tmp_path / 'joint_limits.yaml'
    limits.write_text('joint_limits:\n  joint1: {has_acceleration_limits: true, '
                      'max_acceleration: 0.05}\n', encoding='utf-8')
    common = ['plan', *TARGET, '--json', '--trajectory', '--max-acceleration', '0.5']
    assert main([*common, '--profile', 'trapezoidal', '--joint-limits', str(limits)]) == 0
    record = json.loads(capsys.readouterr().out)
    assert (record['profile'], record['timing']) == ('trapezoidal', 'independent')
    points = record['trajectory']['points']
    assert all(len(p['velocities']) == 5 and p['accelerations'] == [] for p in points)
    assert points[-1]['velocities'] == [0.0] * 5
    assert points[-1]['time_from_start'] >= record['motion_time_s']
    assert main([*common, '--profile', 'jerk_limited', '--max-jerk', '2',
                 '--timing', 'synchronized']) == 0
    record = json.loads(capsys.readouterr().out)
    assert record['timing'] == 'synchronized'
    assert all(len(p['accelerations']) == 5 for p in record['trajectory']['points'])
    assert main(['plan', *TARGET, '--profile', 'trapezoidal', '--max-acceleration', '0.5']) == 0
    assert 's (trapezoidal, independent), position error' in capsys.readouterr().out


def test_plan_a_joint_goal(capsys):
    assert main(['plan', '--joint-goal', '0.5', '-0.3', '0.4', '0.2', '0.1', '--json']) == 0
    record = json.loads(capsys.readouterr().out)
    assert record['status'] == 'succeeded' and record['joint_goal'] == [0.5, -0.3, 0.4, 0.2, 0.1]
    assert record['message'] == 'reached the joint goal in 2.5000 s of motion'
    assert main(['plan', '--joint-goal', '5', '0', '0', '0', '0']) == 1
    assert 'rejected: joint goal joint1 = 5 rad is outside its limits' in capsys.readouterr().out
    assert main(['plan', '0.1', '0.1', '0.1', '--joint-goal', '0', '0', '0', '0', '0']) == 2
    assert '--joint-goal Q..., one of them' in capsys.readouterr().err
