# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The goal as one object: its kinds, its frame, joint goals by name, and the old keywords."""
import numpy as np
import pytest
from trajplan_ros import Goal, Mode, paper_arm, plan, PlanRequest, PlanStatus
from trajplan_ros.kinematics.rotations import quaternion_of_turn, rotation_matrix

ARM = paper_arm()
TARGET = (0.151171, 0.19162, 0.172124)


def test_a_goal_says_its_kind_and_its_tolerances_in_force() -> None:
    assert Goal(TARGET).kind == 'free'
    assert Goal(joint_goal=[0.1] * 5).kind == 'joints'
    assert Goal(TARGET, 'approach').axis_limit == 1e-3
    assert Goal(TARGET, 'radial', axis_tolerance=0.2).angle_limit == 0.2
    pose = Goal(TARGET, Mode.POSE, orientation=(0, 0, 0, 1), orientation_tolerance=0.3)
    assert (pose.kind, pose.angle_limit) == ('pose', 0.3)


def test_plan_keywords_and_the_goal_object_make_the_same_plan() -> None:
    by_keywords = plan(TARGET, mode='radial', seed=4, tolerance=1e-6)
    by_goal = plan(PlanRequest(Goal(TARGET, Mode.RADIAL, tolerance=1e-6), seed=4))
    assert by_keywords.success and by_goal.success
    np.testing.assert_array_equal(by_keywords.joint_goal, by_goal.joint_goal)


def test_moved_turns_and_shifts_the_point_and_orientation_not_the_approach() -> None:
    turn = quaternion_of_turn((0.0, 0.0, np.pi / 2))
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rotation_matrix(turn), (1.0, 2.0, 3.0)
    goal = Goal((0.1, 0.0, 0.0), Mode.POSE, approach=(1, 0, 0), orientation=(0, 0, 0, 1),
                frame='camera').moved(pose)
    np.testing.assert_allclose(goal.position, (1.0, 2.1, 3.0), atol=1e-15)
    np.testing.assert_allclose(rotation_matrix(goal.orientation), rotation_matrix(turn),
                               atol=1e-15)
    assert goal.approach == (1.0, 0.0, 0.0) and goal.frame == ''


def test_an_approach_along_an_orientation_takes_its_z_axis() -> None:
    turn = quaternion_of_turn((np.pi, 0.0, 0.0))          # z points down
    goal = Goal(TARGET, Mode.APPROACH, approach=(1, 0, 0), orientation=turn)
    np.testing.assert_allclose(goal.approach_direction, (0.0, 0.0, -1.0), atol=1e-15)
    np.testing.assert_allclose(Goal(TARGET, Mode.APPROACH, approach=(0, 2, 0)).approach_direction,
                               (0.0, 1.0, 0.0))


def test_a_goal_in_another_frame_is_refused_with_the_way_to_move_it() -> None:
    result = plan(Goal(TARGET, frame='camera_link'))
    assert result.status is PlanStatus.REJECTED
    assert "frame 'camera_link'" in result.message and 'Goal.moved' in result.message


def test_a_joint_goal_by_name_moves_those_joints_and_keeps_the_others() -> None:
    start = np.array([0.1, 0.2, 0.3, 0.4, 0.5])
    named = {ARM.joint_names[1]: -0.4, ARM.joint_names[3]: 0.6}
    result = plan(PlanRequest(Goal(joint_goal=named), start))
    assert result.success, result.message
    np.testing.assert_array_equal(result.joint_goal, [0.1, -0.4, 0.3, 0.6, 0.5])
    unknown = plan(PlanRequest(Goal(joint_goal={'elbow': 0.1}), start))
    assert unknown.status is PlanStatus.REJECTED
    assert 'joint goal names elbow' in unknown.message


@pytest.mark.parametrize('goal, reason', [
    (Goal(TARGET, tolerance=0.0), 'tolerance must be finite and positive'),
    (Goal(TARGET, 'free', orientation=(0, 0, 0, 1)), 'an orientation is for pose and approach'),
    (Goal(TARGET, frame=3), 'frame must be a frame name'),
])
def test_a_goal_that_is_not_one_is_refused_with_the_reason(goal: Goal, reason: str) -> None:
    with pytest.raises(ValueError, match=reason):
        goal.validate()
