# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The node's parameter table, its params.yaml and its checking, without DDS.

``ros.settings.PARAMETERS`` is what the node declares; ``config/params.yaml`` must list every
one of them with the same default, so that the file a user copies is the node's truth.
"""
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from trajplan_ros import paper_arm
from trajplan_ros.kinematics import InvalidArmModel
from trajplan_ros.ros.settings import default_values, PARAMETERS, Settings
from trajplan_ros.tools.bench.cases import PUBLISHED
import yaml


PARAMS_YAML = Path(__file__).resolve().parents[1] / 'config' / 'params.yaml'


def flatten(tree: dict[str, Any], prefix: str = '') -> dict[str, Any]:
    """Nested YAML keys as the dotted parameter names ROS gives them."""
    out: dict[str, Any] = {}
    for key, value in tree.items():
        if isinstance(value, dict):
            out.update(flatten(value, f'{prefix}{key}.'))
        else:
            out[f'{prefix}{key}'] = value
    return out


def test_params_yaml_lists_every_parameter_with_its_default() -> None:
    document = yaml.safe_load(PARAMS_YAML.read_text(encoding='utf-8'))
    assert list(document) == ['/**']                 # any node name, any namespace
    values = flatten(document['/**']['ros__parameters'])
    assert values == default_values()
    # the same types too: ROS refuses an integer where a double was declared
    for name, value in values.items():
        expected = default_values()[name]
        assert type(value) is type(expected), name
        if isinstance(value, list):
            assert [type(v) for v in value] == [type(v) for v in expected], name


def test_every_parameter_has_a_description_and_a_unique_name() -> None:
    names = [spec.name for spec in PARAMETERS]
    assert len(names) == len(set(names))
    assert all(spec.description for spec in PARAMETERS)
    for spec in PARAMETERS:
        if spec.bounds is not None:
            assert spec.bounds[0] <= spec.default <= spec.bounds[1], spec.name
        if spec.choices:
            assert spec.default in spec.choices, spec.name


def test_defaults_give_the_paper_arm() -> None:
    settings = Settings.from_parameters(default_values())
    arm = paper_arm()
    for key in ('rotations', 'translations', 'base', 'sign', 'offset', 'lower', 'upper'):
        np.testing.assert_array_equal(getattr(settings.arm, key), getattr(arm, key))
    assert settings.arm.joint_names == arm.joint_names
    r = settings.request
    assert (r.angular_velocity, r.goal.mode, r.algorithm, r.seed) == (0.2, 'free', 'iepso', 0)
    np.testing.assert_array_equal(settings.start, np.zeros(5))


@pytest.mark.parametrize('change, error, reason', [
    ({'mode': 'sideways'}, ValueError,
     r"mode must be one of free, radial, approach, got 'sideways'"),
    ({'algorithm': 'sa'}, ValueError, r'algorithm must be one of iepso, pso, spso, ga, de'),
    ({'base_frame': ''}, ValueError, r'base_frame must not be empty'),
    ({'start_positions': [0.0] * 3}, ValueError,
     r'start_positions: a start needs 5 joint angles \(or the 4 planned ones\), got 3'),
    ({'start_positions': [0.0, np.nan, 0, 0, 0]}, ValueError, r'non-finite angle'),
    ({'arm.sign': [1, 1, 1, 2, 1]}, InvalidArmModel, r'sign must be \+1 or -1'),
    ({'arm.planned': 6}, InvalidArmModel, r'planned joints must be between 2 and 5'),
    ({'profile': 'smooth'}, ValueError, r'profile must be one of servo, trapezoidal, '
                                        r'jerk_limited'),
    ({'profile': 'trapezoidal'}, ValueError,
     r'the trapezoidal profile needs an acceleration limit for joint joint1: none in the joint '
     r'limits and no max_acceleration given'),
    ({'profile': 'jerk_limited', 'max_acceleration': 2.0}, ValueError,
     r'needs a jerk limit for joint joint1'),
    ({'joint_limits_file': '/nonexistent/joint_limits.yaml'}, ValueError,
     r'cannot read joint limits /nonexistent/joint_limits.yaml'),
])
def test_bad_values_are_refused_with_the_reason(change, error, reason) -> None:
    with pytest.raises(error, match=reason):
        Settings.from_parameters({**default_values(), **change})


def test_seed_minus_one_means_a_fresh_seed() -> None:
    assert Settings.from_parameters({**default_values(), 'seed': -1}).request.seed is None


def test_start_positions_may_give_the_planned_joints_only() -> None:
    settings = Settings.from_parameters({**default_values(), 'start_positions': [0.1] * 4})
    np.testing.assert_array_equal(settings.start, [0.1, 0.1, 0.1, 0.1, 0.0])


def test_a_described_arm_never_reads_a_file_the_description_names(tmp_path) -> None:
    secret = tmp_path / 'secret.urdf'
    secret.write_text('<robot name="x"><link name="a"/></robot>')
    # read as a file it would be a well-formed URDF, refused for its chain instead
    with pytest.raises(ValueError, match='not well-formed XML'):
        Settings.from_parameters({**default_values(), 'robot_description': str(secret)})


def test_start_positions_that_do_not_fit_a_described_chain() -> None:
    so101 = PUBLISHED['so101'].urdf.read_text(encoding='utf-8')
    values = {**default_values(), 'start_positions': [0.1, 0.2, 0.3],
              'tip_link': 'gripper_frame_link'}
    with pytest.raises(ValueError, match='start_positions: a start needs 5 joint angles'):
        Settings.from_parameters(values, so101)
    lenient = Settings.from_parameters(values, so101, strict_start=False)
    assert lenient.start_ignored and lenient.arm.n_joints == 5
    np.testing.assert_array_equal(lenient.start,
                                  np.clip(np.zeros(5), lenient.arm.lower, lenient.arm.upper))
    assert lenient.base_frame == 'base_link'


def test_the_motion_comes_from_its_parameters_and_the_limits_file(tmp_path: Path) -> None:
    limits = tmp_path / 'joint_limits.yaml'
    limits.write_text('joint_limits:\n  joint2:\n    has_acceleration_limits: true\n'
                      '    max_acceleration: 1\n', encoding='utf-8')
    values = {**default_values(), 'profile': 'trapezoidal', 'timing': 'synchronized',
              'joint_limits_file': str(limits), 'max_acceleration': 3.0}
    profile = Settings.from_parameters(values).request.motion
    assert profile.describe() == 'trapezoidal, synchronized'
    law = profile.time_law(paper_arm(), 0.2)
    np.testing.assert_array_equal(law.acceleration, [3.0, 1.0, 3.0, 3.0, 3.0])
    servo = Settings.from_parameters(default_values()).request.motion
    assert servo.describe() == 'servo, independent'
    # the file is read when the parameter is set: a later change of the file, or its removal,
    # does not refuse an unrelated parameter change
    limits.unlink()
    assert Settings.from_parameters({**values, 'seed': 5}).request.motion == profile
    other = tmp_path / 'other_limits.yaml'
    other.write_text('joint_limits:\n  shoulder:\n    has_jerk_limits: true\n    max_jerk: 1\n',
                     encoding='utf-8')
    with_gripper = Settings.from_parameters({**values, 'joint_limits_file': str(other)})
    assert with_gripper.request.motion.ignored_joints(with_gripper.arm) == ['shoulder']
