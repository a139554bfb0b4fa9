# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The node's parts without DDS: work queue, joint_states checks, request checks, diagnostics."""
import math
import threading

from diagnostic_msgs.msg import DiagnosticStatus
from nav_msgs.srv import GetPlan
import numpy as np
import pytest
from std_msgs.msg import Header
from trajplan_ros.planning import Goal
from trajplan_ros.ros.diagnostics import Counters, diagnostic_array
from trajplan_ros.ros.joint_states import JointStateMonitor
from trajplan_ros.ros.mailbox import Admission, Job, Mailbox
from trajplan_ros.ros.node import request_problem
from trajplan_ros.ros.settings import default_values, Settings
from trajplan_ros.ros.transforms import frame_pose, frame_problem

#: The node's settings with every parameter at its default (the paper's arm).
SETTINGS = Settings.from_parameters(default_values())


ARM = ('joint1', 'joint2', 'joint3')


def call(n: int) -> Job:
    return Job(f'service call #{n}', Goal((0.1 * n, 0.0, 0.0)), future=object())


def goal(n: int) -> Job:
    return Job(f'goal #{n}', Goal((0.0, 0.1 * n, 0.0)))


def test_calls_come_out_in_arrival_order_before_the_newest_goal() -> None:
    box = Mailbox()
    assert box.put_goal(goal(1)) is None
    superseded = box.put_goal(goal(2))
    assert superseded.label == 'goal #1'
    for n in range(1, 4):
        assert box.put_call(call(n), limit=10) is Admission.QUEUED
    assert [box.take().label for _ in range(4)] == [
        'service call #1', 'service call #2', 'service call #3', 'goal #2']


def test_calls_beyond_the_limit_are_refused_and_close_hands_back_the_rest() -> None:
    box = Mailbox()
    assert [box.put_call(call(n), limit=2) for n in range(1, 4)] == [
        Admission.QUEUED, Admission.QUEUED, Admission.FULL]
    box.put_goal(goal(1))
    assert box.waiting()[0] == 2
    left = box.close()
    assert [j.label for j in left] == ['service call #1', 'service call #2', 'goal #1']
    assert box.put_call(call(4), limit=2) is Admission.CLOSED
    late = goal(2)
    assert box.put_goal(late) is late                     # closed: handed straight back
    assert box.take() is None


def test_take_blocks_until_work_or_close() -> None:
    box = Mailbox()
    taken: list[object] = []
    worker = threading.Thread(target=lambda: taken.append(box.take()))
    worker.start()
    box.put_call(call(1), limit=1)
    worker.join(timeout=10)
    assert [j.label for j in taken] == ['service call #1']
    worker = threading.Thread(target=lambda: taken.append(box.take()))
    worker.start()
    box.close()
    worker.join(timeout=10)
    assert taken[-1] is None


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


@pytest.mark.parametrize('names, positions, kind, text', [
    (['joint1', 'joint2'], [0.0], 'length mismatch', '2 names but 1 positions'),
    (['joint1', 'joint1'], [0.0, 0.1], 'duplicate name', 'duplicate name joint1'),
    (['joint1', 'joint2'], [0.0, math.nan], 'non-finite position',
     'non-finite position for joint2'),
    (['Joint1', 'Joint2'], [0.0, 0.1], 'no arm joint',
     "names none of the arm's joints: got Joint1, Joint2; expected joint1, joint2, joint3"),
])
def test_each_problem_is_logged_at_once_then_counted(names, positions, kind, text) -> None:
    logged: list[str] = []
    clock = FakeClock()
    monitor = JointStateMonitor(logged.append, repeat_period=5.0, clock=clock)
    monitor.update(['joint1'], [0.5], ARM)
    for _ in range(4):                                   # the first now, three repeats
        monitor.update(names, positions, ARM)
        clock.now += 1.0
    assert logged == [f'ignored joint_states: {text}']
    clock.now = 6.0
    monitor.update(names, positions, ARM)                # the period is over: a summary
    assert logged[1] == f'ignored joint_states: {text} (again, 4 times in the last 6 s)'
    assert monitor.counts()[kind] == 5
    assert sum(monitor.counts().values()) == 5
    # nothing of a bad message was taken
    start = monitor.start(ARM, [0.0, 0.0, 0.0])
    assert start.q.tolist() == [0.5, 0.0, 0.0]


def test_the_start_says_where_each_joint_came_from() -> None:
    monitor = JointStateMonitor(lambda _: None)
    start = monitor.start(ARM, [0.1, 0.2, 0.3])
    assert start.q.tolist() == [0.1, 0.2, 0.3]
    assert start.describe() == ''                        # one source: nothing to say
    monitor.trajectory_ended(ARM, [1.0, 2.0, 3.0])
    monitor.update(['other_robot_joint', 'joint2'], [9.0, -2.0], ARM)
    start = monitor.start(ARM, [0.1, 0.2, 0.3])
    assert start.q.tolist() == [1.0, -2.0, 3.0]
    assert start.describe() == ' [joint1, joint3 from trajectory end; joint2 from joint_states]'
    monitor.forget()                                     # another arm: the names mean others
    assert monitor.start(ARM, [0.1, 0.2, 0.3]).q.tolist() == [0.1, 0.2, 0.3]


def request(tolerance: float, frame: str = '') -> GetPlan.Request:
    r = GetPlan.Request(tolerance=tolerance)
    r.goal.header.frame_id = frame
    return r


@pytest.mark.parametrize('tolerance', [-1.0, math.inf, math.nan])
def test_bad_tolerances_are_refused(tolerance) -> None:
    assert 'is not allowed' in request_problem(request(tolerance), SETTINGS)


def test_zero_and_positive_tolerances_and_the_robots_frames_pass() -> None:
    for r in (request(0.0), request(1e-3, 'base_link'), request(0.0, ''),
              request(0.0, 'link3')):                   # a link of the paper arm's URDF
        assert request_problem(r, SETTINGS) is None


def test_a_goal_in_a_frame_the_robot_does_not_have_is_refused() -> None:
    reason = request_problem(request(0.0, 'map'), SETTINGS)
    assert reason.startswith("frame 'map' is not a link of the robot; known frames: base_link")
    assert reason.endswith('(other frames need tf2)')


def test_diagnostics_warn_on_slow_calls_and_superseded_goals() -> None:
    counters = Counters()
    for name, n in (('goals_received', 5), ('goals_planned', 3), ('goals_superseded', 2),
                    ('calls_received', 4), ('calls_answered', 4)):
        counters.add(name, n)
    counters.plan_time(0.01)
    problems = {'length mismatch': 1, 'non-finite position': 0}

    def status(waiting: int, oldest: float) -> DiagnosticStatus:
        array = diagnostic_array('/trajplan', Header(), counters.snapshot(), waiting, oldest,
                                 counters.superseded_since_last_report(), problems)
        return array.status[0]

    first = status(0, 0.0)
    assert first.level == DiagnosticStatus.WARN and '2 goal(s) superseded' in first.message
    values = {kv.key: kv.value for kv in first.values}
    assert values['goals_received'] == '5' and values['goals_superseded'] == '2'
    assert values['joint_states length mismatch'] == '1'
    assert values['last_plan_time_s'] == '0.01'
    assert status(0, 0.0).level == DiagnosticStatus.OK   # nothing superseded since
    slow = status(3, 1.5)
    assert slow.level == DiagnosticStatus.WARN and 'waited 1.5 s' in slow.message
    assert {kv.key: kv.value for kv in slow.values}['calls_waiting'] == '3'


def test_other_robots_joints_are_not_checked_and_repeats_are_flushed() -> None:
    logged: list[str] = []
    clock = FakeClock()
    monitor = JointStateMonitor(logged.append, repeat_period=5.0, clock=clock)
    # a gripper's NaN or a duplicate gripper name is not ours: the arm's joints are taken
    monitor.update(['joint1', 'gripper', 'gripper'], [0.3, math.nan, 0.0], ARM)
    assert logged == [] and monitor.start(ARM, [0.0] * 3).q.tolist() == [0.3, 0.0, 0.0]
    # the same kind with another text is a repeat; the timer flushes what is left
    monitor.update(['joint2'], [math.inf], ARM)
    monitor.update(['joint3'], [math.nan], ARM)
    monitor.flush_repeats()
    assert logged == ['ignored joint_states: non-finite position for joint2']
    clock.now = 5.0
    monitor.flush_repeats()
    assert logged[1] == ('ignored joint_states: non-finite position for joint3 (again, 1 times '
                         'in the last 5 s)')
    monitor.flush_repeats()
    assert len(logged) == 2                              # nothing new to say


class StaticTf:
    """What tf knows, as ``transforms.Transforms`` answers: fixed poses by frame."""

    def __init__(self, poses: dict[str, np.ndarray], newest_only: tuple[str, ...] = ()) -> None:
        self.poses, self.newest_only = poses, newest_only

    def knows(self, target: str, frame: str) -> bool:
        return frame in self.poses or frame in self.newest_only

    def pose(self, target: str, frame: str, stamp: tuple[int, int], timeout: float,
             stop: object = None) -> np.ndarray:
        if frame not in self.poses:
            raise ValueError(f"frame '{frame}' has no transform")
        return self.poses[frame]


def test_a_frame_is_posed_by_tf_where_tf_knows_it_else_by_the_urdf() -> None:
    angles = dict(zip(SETTINGS.arm.joint_names, [0.3, -0.2, 0.4, 0.1, 0.0]))
    link = SETTINGS.frames.links[-1]
    by_fk = SETTINGS.frames.to_base(link, angles)
    camera = np.eye(4)
    camera[:3, 3] = (0.1, 0.2, 0.3)
    np.testing.assert_array_equal(frame_pose('', SETTINGS, angles, None), np.eye(4))
    np.testing.assert_array_equal(frame_pose(link, SETTINGS, angles, None), by_fk)
    tf = StaticTf({'camera_link': camera})
    np.testing.assert_array_equal(frame_pose('camera_link', SETTINGS, angles, tf), camera)
    np.testing.assert_array_equal(frame_pose(link, SETTINGS, angles, tf), by_fk)   # not in tf
    np.testing.assert_array_equal(frame_pose(link, SETTINGS, angles, StaticTf({link: camera})),
                                  camera)                                          # tf wins
    np.testing.assert_array_equal(frame_pose(link, SETTINGS, angles, StaticTf({}, (link,)),
                                             (5, 0)), by_fk)     # not at the stamp: the URDF
    with pytest.raises(ValueError, match="frame 'camera_link' is not a link of the robot; .* "
                                         r'\(other frames need tf2\)'):
        frame_pose('camera_link', SETTINGS, angles, None)
    with pytest.raises(ValueError, match="frame 'nowhere' has no transform"):
        frame_pose('nowhere', SETTINGS, angles, tf)
    assert frame_problem('nowhere', SETTINGS, with_tf=True) is None
    assert 'need tf2' in frame_problem('nowhere', SETTINGS, with_tf=False)
