# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The motion's settings: profile, timing, and each joint's limits from where ROS keeps them."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from trajplan_ros import ArmModel, paper_arm, plan
from trajplan_ros.motion.motion_profile import (JointLimits, MotionProfile, Profile,
                                                read_joint_limits, Timing)
from trajplan_ros.motion.time_law import JERK_LIMITED, joint_time, SERVO, TRAPEZOIDAL

#: MoveIt's format, as a moveit_config package has it (nested variant below).
LIMITS = """
default_velocity_scaling_factor: 0.1
joint_limits:
  joint1:
    has_velocity_limits: true
    max_velocity: 0.1
    has_acceleration_limits: true
    max_acceleration: 2
    has_jerk_limits: false
    max_jerk: -5            # ignored: has_jerk_limits is false
  joint2:
    has_acceleration_limits: true
    max_acceleration: 1.5
    has_jerk_limits: true
    max_jerk: 30.0
  joint3:
    has_velocity_limits: false
    max_velocity: .nan      # ignored
"""


def write(tmp_path: Path, text: str) -> Path:
    """Write ``text`` to a joint_limits.yaml in tmp_path; return its path."""
    path = tmp_path / 'joint_limits.yaml'
    path.write_text(text, encoding='utf-8')
    return path


def test_limits_are_read_as_moveit_writes_them(tmp_path: Path) -> None:
    limits = read_joint_limits(write(tmp_path, LIMITS))
    assert limits == {'joint1': JointLimits(velocity=0.1, acceleration=2.0),
                      'joint2': JointLimits(acceleration=1.5, jerk=30.0),
                      'joint3': JointLimits()}
    assert isinstance(limits['joint1'].acceleration, float)          # an integer accepted
    nested = 'robot_description_planning:\n' + ''.join(
        '  ' + line + '\n' for line in LIMITS.strip().splitlines())
    assert read_joint_limits(write(tmp_path, nested)) == limits


@pytest.mark.parametrize('text, reason', [
    ('joint_limits:\n  joint1:\n    has_acceleration_limits: true\n    max_acceleration: -1\n',
     'joint_limits.joint1.max_acceleration must be finite and positive, got -1'),
    ('joint_limits:\n  joint1:\n    has_jerk_limits: true\n    max_jerk: .nan\n',
     'joint_limits.joint1.max_jerk must be finite and positive'),
    ('joint_limits:\n  joint1:\n    has_velocity_limits: true\n',
     'has_velocity_limits is true but max_velocity is missing'),
    ('joint_limits:\n  joint1:\n    has_velocity_limits: yes please\n',
     'has_velocity_limits must be true or false'),
    ('joint_limits:\n  joint1:\n    has_velocity_limits: true\n    max_velocity: fast\n',
     'max_velocity must be a number'),
    ('joint_limits: [1, 2]\n', 'has no joint_limits: mapping'),
    ('joint_limits:\n  joint1: [\n', 'cannot parse joint limits'),
    ('joint_limits:\n  joint1: 3\n', 'joint_limits.joint1 must be a mapping'),
])
def test_bad_limits_get_a_one_line_reason(tmp_path: Path, text: str, reason: str) -> None:
    with pytest.raises(ValueError, match=reason.replace('.', r'\.')) as info:
        read_joint_limits(write(tmp_path, text))
    assert '\n' not in str(info.value)


def test_a_missing_file_gets_a_reason(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match='cannot read joint limits .*nope.yaml'):
        read_joint_limits(tmp_path / 'nope.yaml')


def test_each_joint_takes_its_own_limit_then_the_setting_and_omega_caps_velocity(
        tmp_path: Path) -> None:
    arm = paper_arm()                 # joints joint1..joint5, no URDF velocity limit
    profile = MotionProfile.from_file(write(tmp_path, LIMITS), profile='jerk_limited',
                                      max_acceleration=4.0, max_jerk=50.0)
    law = profile.time_law(arm, omega=0.2)
    assert law.kind == JERK_LIMITED
    # the file's default_velocity_scaling_factor 0.1 scales every velocity limit
    np.testing.assert_allclose(law.velocity, 0.1 * np.array([0.1, 0.2, 0.2, 0.2, 0.2]))
    np.testing.assert_array_equal(law.acceleration, [2.0, 1.5, 4.0, 4.0, 4.0])
    np.testing.assert_array_equal(law.jerk, [50.0, 30.0, 50.0, 50.0, 50.0])
    trapezoidal = MotionProfile('trapezoidal', max_acceleration=4.0).time_law(arm, 0.2)
    assert trapezoidal.kind == TRAPEZOIDAL and np.all(trapezoidal.jerk == np.inf)


def test_the_urdf_velocity_counts_unless_the_file_sets_one(tmp_path: Path) -> None:
    p = paper_arm()
    arm = ArmModel.from_dh(*p.dh, sign=p.sign, offset=p.offset, lower=p.lower, upper=p.upper,
                           velocity=[0.05, 0.05, 1.0, 0.1, 1.0], planned=4)
    law = MotionProfile.from_file(write(tmp_path, LIMITS)).time_law(arm, omega=0.2)
    assert law.kind == SERVO
    np.testing.assert_allclose(law.velocity, 0.1 * np.array([0.1, 0.05, 0.2, 0.1, 0.2]))
    np.testing.assert_array_equal(law.acceleration, np.inf)


def test_a_profile_without_the_limits_it_needs_is_refused_naming_the_joint(
        tmp_path: Path) -> None:
    profile = MotionProfile.from_file(write(tmp_path, LIMITS), profile='trapezoidal')
    with pytest.raises(ValueError, match='trapezoidal profile needs an acceleration limit for '
                                         'joint joint3: none in the joint limits and no '
                                         'max_acceleration given'):
        profile.time_law(paper_arm(), 0.2)
    with pytest.raises(ValueError, match='jerk limit for joint joint1'):
        MotionProfile('jerk_limited', max_acceleration=1.0).time_law(paper_arm(), 0.2)
    with pytest.raises(ValueError, match='needs a jerk limit'):                # plan() too
        plan([0.15, 0.19, 0.17], motion=MotionProfile('jerk_limited', max_acceleration=1.0))


def test_limits_of_a_joint_the_arm_does_not_have_are_ignored_and_named() -> None:
    gripper = {'gripper': JointLimits(velocity=1.0, acceleration=1.0)}
    profile = MotionProfile('trapezoidal', max_acceleration=2.0, joint_limits=gripper)
    assert profile.ignored_joints(paper_arm()) == ['gripper']
    law = profile.time_law(paper_arm(), 0.2)
    plain = MotionProfile('trapezoidal', max_acceleration=2.0).time_law(paper_arm(), 0.2)
    for mine, expected in zip(law, plain):
        np.testing.assert_array_equal(mine, expected)


def test_scaling_factors_scale_velocity_and_acceleration_as_moveit_does(
        tmp_path: Path) -> None:
    """A request's scaling wins over the file's default; jerk is not scaled; (0, 1] only."""
    arm = paper_arm()
    path = write(tmp_path, LIMITS.replace('default_velocity_scaling_factor: 0.1',
                                          'default_velocity_scaling_factor: 0.1\n'
                                          'default_acceleration_scaling_factor: 0.5'))
    settings = {'profile': 'jerk_limited', 'max_acceleration': 4.0, 'max_jerk': 50.0}
    full = MotionProfile.from_file(path, velocity_scaling=1.0, acceleration_scaling=1.0,
                                   **settings).time_law(arm, 0.2)
    by_file = MotionProfile.from_file(path, **settings)
    assert (by_file.velocity_scaling, by_file.acceleration_scaling) == (0.1, 0.5)
    law = by_file.time_law(arm, 0.2)
    np.testing.assert_allclose(law.velocity, 0.1 * full.velocity)
    np.testing.assert_allclose(law.acceleration, 0.5 * full.acceleration)
    np.testing.assert_array_equal(law.jerk, full.jerk)
    mine = MotionProfile.from_file(path, velocity_scaling=0.3, **settings)
    assert (mine.velocity_scaling, mine.acceleration_scaling) == (0.3, 0.5)
    assert mine.describe() == 'jerk_limited, independent, velocity x0.3, acceleration x0.5'
    for bad in (0.0, 1.5, float('nan')):
        with pytest.raises(ValueError, match='velocity_scaling'):
            MotionProfile(velocity_scaling=bad)
    # plan() takes them as keywords: half the speed, twice the servo motion time
    fast, slow = plan([0.15, 0.19, 0.17], seed=1), plan([0.15, 0.19, 0.17], seed=1,
                                                        velocity_scaling=0.5)
    assert slow.motion_time_s == pytest.approx(2 * fast.motion_time_s, rel=1e-9)


@pytest.mark.parametrize('settings, reason', [
    ({'profile': 'smooth'}, "unknown profile 'smooth'; choose from servo, trapezoidal, "
                            'jerk_limited'),
    ({'timing': 'together'}, "unknown timing 'together'"),
    ({'max_acceleration': 0.0}, 'max_acceleration must be finite and positive, got 0.0'),
    ({'max_jerk': float('inf')}, 'max_jerk must be finite and positive'),
    ({'max_jerk': True}, 'max_jerk must be a number'),
])
def test_bad_settings_are_refused(settings: dict, reason: str) -> None:
    with pytest.raises(ValueError, match=reason):
        MotionProfile(**settings)


def test_settings_take_their_enums_and_say_what_they_are() -> None:
    profile = MotionProfile('trapezoidal', 'synchronized', max_acceleration=2)
    assert profile.profile is Profile.TRAPEZOIDAL and profile.timing is Timing.SYNCHRONIZED
    assert profile.max_acceleration == 2.0 and profile.describe() == 'trapezoidal, synchronized'
    assert MotionProfile().describe() == 'servo, independent'


def test_the_installed_example_limits_are_read_and_planned_with() -> None:
    example = Path(__file__).resolve().parents[1] / 'config' / 'paper_arm_joint_limits.yaml'
    limits = read_joint_limits(example)
    assert sorted(limits) == list(paper_arm().joint_names)
    for name in ('trapezoidal', 'jerk_limited'):
        profile = MotionProfile.from_file(example, profile=name, timing='synchronized')
        result = plan([0.151171, 0.19162, 0.172124], motion=profile, seed=1)
        assert result.success, result.message
        law = profile.time_law(paper_arm(), 0.2)
        slowest = max(joint_time(law, i, abs(result.joint_goal[i])) for i in range(4))
        assert result.motion_time_s == pytest.approx(slowest, rel=1e-12)
