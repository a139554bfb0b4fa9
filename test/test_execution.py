# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""What the node says of an execution through FollowJointTrajectory, without DDS."""
from __future__ import annotations

from action_msgs.msg import GoalStatus
from diagnostic_msgs.msg import DiagnosticStatus
import pytest
from trajplan_ros.ros import outcomes
from trajplan_ros.ros.execution import (describe_end, position_error, result_status,
                                        start_mismatch)

NAMES = ('shoulder_pan', 'shoulder_lift', 'elbow_flex')


def test_a_start_within_tolerance_is_sent_and_one_beyond_names_both_states() -> None:
    planned = [0.1, 0.2, 0.3]
    assert start_mismatch(NAMES, planned, dict(zip(NAMES, [0.12, 0.2, 0.29])), 0.05) is None
    why = start_mismatch(NAMES, planned, dict(zip(NAMES, [0.1, 0.35, 0.3])), 0.05)
    assert why.startswith('the plan starts 0.15 rad from joint_states on shoulder_lift '
                          '(start_tolerance 0.05 rad)')
    assert 'planned from (0.1000, 0.2000, 0.3000), joint_states (0.1000, 0.3500, 0.3000)' in why


def test_an_unknown_state_is_refused_unless_the_check_is_off() -> None:
    why = start_mismatch(NAMES, [0.0] * 3, {'shoulder_pan': 0.0}, 0.05)
    assert why.startswith('no joint_states for shoulder_lift, elbow_flex')
    assert start_mismatch(NAMES, [0.0] * 3, {}, 0.0) is None


def test_the_position_error_is_the_largest_joint_difference() -> None:
    goal = dict(zip(NAMES, [0.1, 0.2, 0.3]))
    assert position_error(goal, dict(zip(NAMES, [0.1, 0.17, 0.31]))) == (
        pytest.approx(0.03), 'shoulder_lift')
    assert position_error(goal, {'shoulder_pan': 0.1}) == (None, '')


@pytest.mark.parametrize('goal_status, code, preempted, stopping, status', [
    (GoalStatus.STATUS_SUCCEEDED, 0, False, False, 'executed'),
    (GoalStatus.STATUS_ABORTED, -4, False, False, 'path_tolerance_violated'),
    (GoalStatus.STATUS_ABORTED, -5, False, False, 'goal_tolerance_violated'),
    (GoalStatus.STATUS_ABORTED, -1, False, False, 'invalid_goal'),
    (GoalStatus.STATUS_ABORTED, -2, False, False, 'invalid_joints'),
    (GoalStatus.STATUS_ABORTED, -3, False, False, 'old_header_timestamp'),
    (GoalStatus.STATUS_ABORTED, 0, False, False, 'aborted'),
    (GoalStatus.STATUS_ABORTED, -7, False, False, 'aborted'),
    (GoalStatus.STATUS_SUCCEEDED, -5, False, False, 'goal_tolerance_violated'),
    (GoalStatus.STATUS_CANCELED, 0, True, False, 'preempted'),
    (GoalStatus.STATUS_ABORTED, 0, True, False, 'preempted'),
    (GoalStatus.STATUS_CANCELED, 0, False, True, 'shut_down'),
    (GoalStatus.STATUS_CANCELED, 0, False, False, 'cancelled'),
])
def test_each_result_is_named(goal_status: int, code: int, preempted: bool, stopping: bool,
                              status: str) -> None:
    assert result_status(goal_status, code, preempted, stopping) == status
    assert status in outcomes.TERMINAL


def test_an_end_says_where_the_arm_stopped_and_what_the_controller_said() -> None:
    assert describe_end('goal tolerance violated', 0.03, 'wrist_flex',
                        'Aborted due to goal tolerance violation') == (
        'goal tolerance violated (0.03 rad from the goal on joint wrist_flex); controller: '
        'Aborted due to goal tolerance violation')
    assert describe_end('rejected', None, '', '') == 'rejected'


def test_an_execution_status_is_its_own_stage_with_the_controllers_result() -> None:
    msg = outcomes.outcome_status('/trajplan: goal #2', 'goal', None, (0.1, 0.2, 0.3),
                                  'goal_tolerance_violated', 'goal tolerance violated',
                                  execution=outcomes.Execution(-5, 'Aborted', 0.03, 'joint5'))
    values = outcomes.outcome_values(msg)
    assert msg.level == DiagnosticStatus.ERROR
    assert (values['stage'], values['error_code'], values['error_string'],
            values['position_error_rad'], values['position_error_joint']) == (
        'execution', '-5', 'Aborted', '0.03', 'joint5')
    planned = outcomes.outcome_values(outcomes.outcome_status(
        '/trajplan: goal #2', 'goal', None, (0.1, 0.2, 0.3), 'succeeded', 'reached'))
    assert (planned['stage'], planned['error_code'], planned['position_error_rad']) == (
        'plan', '', '')
    accepted = outcomes.outcome_status('n', 'goal', None, (0, 0, 0), 'accepted', 'accepted',
                                       execution=outcomes.Execution())
    assert accepted.level == DiagnosticStatus.OK and 'accepted' not in outcomes.TERMINAL
