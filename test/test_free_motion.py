# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Collision-free planning on the paper's arm and on an arm of concave meshes.

The continuous check of a motion and the search for the fastest free joint goal, checked against
python-fcl (``IndependentCheck``).
"""
from mesh_arm import write_mesh_arm
import numpy as np
import pytest
from trajplan_ros import ArmModel, paper_arm, plan, PlanStatus
from trajplan_ros.collision.distances import ArmCollision, CollisionWorld
from trajplan_ros.collision.free_motion import check_motion, START_TOLERANCE
from trajplan_ros.collision.scene import Scene
from trajplan_ros.kinematics.jit import kernels
from trajplan_ros.kinematics.urdf_export import urdf_xml
from trajplan_ros.motion.motion_profile import MotionProfile, Timing
from trajplan_ros.motion.trajectory import motion_states
from trajplan_ros.planning import prepare
from trajplan_ros.tools.bench.clearance import IndependentCheck

TARGET = (0.151171, 0.19162, 0.172124)
ARM = paper_arm()
URDF = urdf_xml(ARM, velocity=0.2)


@pytest.fixture(scope='module')
def model() -> ArmCollision:
    return ArmCollision.from_urdf(URDF, ARM)


@pytest.fixture(scope='module')
def urdf_file(tmp_path_factory: pytest.TempPathFactory):
    path = tmp_path_factory.mktemp('arm') / 'paper_arm.urdf'
    path.write_text(URDF)
    return path


def world_of(model: ArmCollision, *obstacles: dict, padding: float = 0.01) -> CollisionWorld:
    return CollisionWorld(model, Scene.from_dict({'obstacles': list(obstacles)}), padding)


def sampled(start: np.ndarray, goal: np.ndarray, step: float) -> np.ndarray:
    """Return the planned motion's joint angles every ``step`` seconds, the end included."""
    law = MotionProfile().time_law(ARM, 0.2)
    duration = np.max(np.abs(goal - start) / law.velocity)
    t = np.append(np.arange(0.0, duration, step), duration)
    return motion_states(start, goal, law, Timing.INDEPENDENT, t)[0]


def motion_check(world: CollisionWorld, start: np.ndarray, goal: np.ndarray):
    return check_motion(world, start, goal, MotionProfile().time_law(ARM, 0.2),
                        Timing.INDEPENDENT)


def test_without_a_scene_the_plan_is_the_same(model: ArmCollision) -> None:
    free = plan(TARGET, seed=3)
    checked = plan(TARGET, seed=3, world=world_of(model))
    assert checked.status is PlanStatus.SUCCEEDED
    np.testing.assert_array_equal(checked.joint_goal, free.joint_goal)
    assert checked.clearance_m > 0.01 and ' with ' in checked.clearance_pair


def test_an_obstacle_on_the_way_moves_the_plan_to_a_free_motion(
        model: ArmCollision, urdf_file) -> None:
    first = plan(TARGET, seed=1)
    q = sampled(first.start, first.joint_goal, 0.01)
    tool = ARM.tool(q[len(q) // 2][None])[0][0]                  # where the tool passes
    ball = {'id': 'ball', 'type': 'sphere', 'dimensions': [0.02], 'position': tool.tolist()}
    world = world_of(model, ball)
    blocked = motion_check(world, first.start, first.joint_goal)
    assert not blocked.free and "'ball'" in blocked.pair
    result = plan(TARGET, seed=1, world=world)
    assert result.status is PlanStatus.SUCCEEDED, result.message
    assert result.motion_time_s >= first.motion_time_s
    assert result.position_error_m <= 1e-6
    least, pair, _ = IndependentCheck(world, urdf_file).least(
        sampled(result.start, result.joint_goal, 1e-3))
    assert least > world.padding, pair
    assert result.clearance_m >= world.padding and result.clearance_m <= least + 1e-6


def test_a_thin_plate_between_two_checked_instants_is_still_seen(
        model: ArmCollision, urdf_file) -> None:
    first = plan(TARGET, seed=1)
    coarse = sampled(first.start, first.joint_goal, 1.0)
    middle = 0.5 * (ARM.tool(coarse[0][None])[0][0] + ARM.tool(coarse[1][None])[0][0])
    plate = {'id': 'plate', 'type': 'box', 'dimensions': [0.01, 0.01, 0.0005],
             'position': middle.tolist()}
    world = world_of(model, plate, padding=0.0)
    check = IndependentCheck(world, urdf_file)
    assert check.least(coarse)[0] > 0.03                         # 1 Hz samples miss it
    assert check.least(sampled(first.start, first.joint_goal, 1e-3))[0] <= 0.0   # it is hit
    seen = motion_check(world, first.start, first.joint_goal)
    assert not seen.free and "'plate'" in seen.pair


def test_a_goal_inside_an_obstacle_is_rejected(model: ArmCollision) -> None:
    box = {'id': 'crate', 'type': 'box', 'dimensions': [0.05, 0.05, 0.05],
           'position': list(TARGET)}
    result = plan(TARGET, world=world_of(model, box))
    assert result.status is PlanStatus.REJECTED
    assert "inside obstacle 'crate'" in result.message


def test_a_goal_with_no_free_motion_names_the_blocking_pair(model: ArmCollision) -> None:
    below = np.array(TARGET) - (0.0, 0.0, 0.005 + 0.01)          # 5 mm under the goal's point
    slab = {'id': 'slab', 'type': 'box', 'dimensions': [0.2, 0.2, 0.02],
            'position': below.tolist()}
    result = plan(TARGET, seed=2, world=world_of(model, slab))
    assert result.status is PlanStatus.NOT_REACHED
    assert result.message.startswith('every direct motion found collides: ')
    assert "with 'slab'" in result.message


def test_a_start_within_the_padding_may_leave_but_not_come_closer(model: ArmCollision) -> None:
    table = {'id': 'table', 'type': 'box', 'dimensions': [1.0, 1.0, 0.02],
             'position': [0.0, 0.0, -0.03]}
    result = plan(TARGET, seed=1, world=world_of(model, table))
    assert result.status is PlanStatus.SUCCEEDED, result.message
    assert 'starts within the padding' in result.message and "with 'table'" in result.message


def test_a_mesh_arm_plans_around_an_obstacle_by_the_triangles_with_no_new_kernel(
        tmp_path) -> None:
    urdf = write_mesh_arm(tmp_path)
    arm = ArmModel.from_urdf(urdf, 'base_link', 'tip')
    model = ArmCollision.from_urdf(urdf, arm, samples=200)
    start = np.zeros(arm.n_joints)
    goal = arm.tool(np.array([[1.2, 1.0, 0.9]]))[0][0]
    free = plan(goal, start, arm=arm, seed=4)
    law = MotionProfile().time_law(arm, free.angular_velocity)
    middle = motion_states(start, free.joint_goal, law, Timing.INDEPENDENT,
                           np.array([0.5 * free.motion_time_s]))[0][0]
    on_the_way = arm.tool(middle[None])[0][0]                        # where the tool passes
    world = CollisionWorld(model, Scene.from_dict({'obstacles': [
        {'id': 'table', 'type': 'box', 'dimensions': [1.5, 1.5, 0.02],
         'position': [0.0, 0.0, -0.02]},
        {'id': 'ball', 'type': 'sphere', 'dimensions': [0.03],
         'position': on_the_way.tolist()}]}))
    assert not check_motion(world, start, free.joint_goal, law, Timing.INDEPENDENT).free
    prepare()                      # the collision check's kernels are compiled with the rest
    before = {k: len(k.overloads) for k in kernels()}
    result = plan(goal, start, arm=arm, seed=4, world=world)
    assert {k: len(k.overloads) for k in kernels()} == before
    assert result.status is PlanStatus.SUCCEEDED, result.message
    assert result.motion_time_s >= free.motion_time_s
    t = np.append(np.arange(0.0, result.motion_time_s, 1e-3), result.motion_time_s)
    q = motion_states(start, result.joint_goal, law, Timing.INDEPENDENT, t)[0]
    assert IndependentCheck(world, urdf).violations(q, START_TOLERANCE) == []
    assert world.padding <= result.clearance_m <= IndependentCheck(world, urdf).least(q)[0]
