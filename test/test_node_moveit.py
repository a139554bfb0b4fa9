# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
move_group's plan_kinematic_path, over real DDS, as a MoveIt client asks it.

The node runs with ``moveit_interfaces`` and the moveit_msgs the session fixture provides; the
client is ``moveit_client.py`` in a process of its own with the same environment (the request
as pymoveit2's template builds it). The answers are checked on the arm: the trajectory's last
point through forward kinematics, not only the code. Without moveit_msgs (and no sources to
build it) these tests skip with the reason, except the refusal at start, which needs its
absence.
"""
from __future__ import annotations

import json
import math
from pathlib import Path
import re
import subprocess
import sys
from typing import Any, Callable, Iterator

from node_under_test import ARM, NodeProcess
import numpy as np
import pytest
from rclpy.parameter import Parameter
from trajplan_ros.kinematics import ArmModel
from trajplan_ros.kinematics.rotations import quaternions
from trajplan_ros.tools.bench.cases import PUBLISHED
import yaml

pytestmark = pytest.mark.dds

NS = '/moveit'
SERVICE = f'{NS}/plan_kinematic_path'                 # as move_group's: not private
CLIENT = Path(__file__).with_name('moveit_client.py')
REACHABLE = (0.151171, 0.19162, 0.172124)
OUT_OF_REACH = (0.05, -0.05, -0.25)
SO101 = PUBLISHED['so101']
PANDA = PUBLISHED['panda']


@pytest.fixture(scope='module')
def move_group(start_node: Callable[..., NodeProcess],
               moveit_msgs_env: dict[str, str]) -> Iterator[tuple[NodeProcess, dict]]:
    """Run the node as move_group with MoveIt's interfaces on (the paper's arm)."""
    node = start_node('-r', f'__ns:={NS}', '-r', '__node:=move_group', '-p',
                      'moveit_interfaces:=true', '-p', 'angular_velocity:=1.0',
                      ready=False, env=moveit_msgs_env)
    node.wait_for(r"move_group\]: MoveIt's interfaces ready: plan_kinematic_path")
    node.wait_for(r'move_group\]: ready: ')
    yield node, moveit_msgs_env
    assert node.stop() == 0, node.output


def ask(move_group: tuple[NodeProcess, dict], *specs: dict[str, Any]) -> list[dict[str, Any]]:
    """Send each request (``moveit_client.motion_request``'s keywords); return the answers."""
    _, env = move_group
    done = subprocess.run([sys.executable, str(CLIENT), SERVICE, json.dumps(specs)], env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-3000:]
    return [json.loads(line) for line in done.stdout.splitlines()]


def tool_at(positions: list[float]) -> np.ndarray:
    return ARM.tool(np.array([positions]))[0][0]


def test_a_position_goal_is_planned_into_its_sphere_from_the_given_start(move_group) -> None:
    start = {'joint1': 0.2, 'joint2': -0.1, 'finger': 0.01}          # extras ignored
    answer, = ask(move_group, {'position': REACHABLE, 'radius': 0.001, 'start': start})
    assert answer['code'] == 'SUCCESS', answer
    assert answer['source'] == 'trajplan_ros' and answer['message'].startswith('reached')
    assert answer['joint_names'] == list(ARM.joint_names) == answer['start_names']
    assert answer['times'][0] == 0.0 and answer['planning_time'] > 0.0
    first, last = answer['positions'][0], answer['positions'][-1]
    assert first == answer['start'] and first[:2] == [0.2, -0.1]
    assert np.linalg.norm(tool_at(last) - REACHABLE) <= 0.001 + 1e-9
    assert answer['frame'] == 'base_link'                     # the base_frame parameter


def test_a_larger_sphere_is_a_region_the_plan_moves_into_faster(move_group) -> None:
    small, large = ask(move_group, {'position': REACHABLE, 'radius': 0.001},
                       {'position': REACHABLE, 'radius': 0.03})
    assert small['code'] == large['code'] == 'SUCCESS'
    assert np.linalg.norm(tool_at(large['positions'][-1]) - REACHABLE) <= 0.03 + 1e-9
    assert large['times'][-1] < small['times'][-1]            # the least time into the region


def test_of_several_goal_regions_the_fastest_to_move_into_is_planned(move_group) -> None:
    far = (0.2, -0.15, 0.1)
    alone_far, alone_near, both, unreachable_first = ask(
        move_group, {'position': far}, {'position': REACHABLE},
        {'position': far, 'regions': [REACHABLE]},
        {'position': OUT_OF_REACH, 'regions': [far]})
    faster, slower = sorted((alone_far, alone_near), key=lambda a: a['times'][-1])
    assert faster['times'][-1] < slower['times'][-1]
    assert both['code'] == 'SUCCESS' and both['positions'] == faster['positions'], both
    assert unreachable_first['code'] == 'SUCCESS'
    assert unreachable_first['positions'] == alone_far['positions']


def test_an_approach_goal_free_about_z_points_the_tool_axis(move_group) -> None:
    q = np.array([-0.4, 0.5, 0.9, 0.3, 0.0])                    # a tool pose the arm takes
    goal = ARM.frames(q[None])[0, -1]
    turned = goal[:3, :3] @ np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], dtype=float)
    answer, = ask(move_group, {'position': goal[:3, 3].tolist(), 'radius': 0.001,
                               'orientation': quaternions(turned[None])[0].tolist(),
                               'tolerances': [0.01, 0.01, math.pi]})    # any turn about z
    assert answer['code'] == 'SUCCESS', answer
    frame = ARM.frames(np.array([answer['positions'][-1]]))[0, -1]
    axis = frame[:3, :3] @ ARM.tool_axis
    assert math.acos(min(1.0, float(axis @ goal[:3, 2]))) <= 0.01 + 1e-6
    assert np.linalg.norm(frame[:3, 3] - goal[:3, 3]) <= 0.001 + 1e-9


def test_codes_say_why_a_goal_is_not_planned(move_group) -> None:
    node, _ = move_group
    specs = {
        'NO_IK_SOLUTION': {'position': OUT_OF_REACH},
        'INVALID_LINK_NAME': {'position': REACHABLE, 'link': 'no_such_link'},
        'FRAME_TRANSFORM_FAILURE': {'position': REACHABLE, 'frame': 'camera_link'},
        'PLANNING_FAILED': {'position': REACHABLE, 'path_constraint': True},
        'INVALID_GOAL_CONSTRAINTS': {'position': REACHABLE, 'box': [0.1, 0.1]},
        'INVALID_ROBOT_STATE': {'position': REACHABLE, 'start': {'joint1': 9.0}},
        'TIMED_OUT': {'position': REACHABLE, 'planning_time': 1e-6},   # no search is that fast
    }
    answers = ask(move_group, *specs.values())
    for code, answer in zip(specs, answers):
        assert answer['code'] == code, (code, answer)
        assert answer['message'] and answer['source'] == 'trajplan_ros', answer
        assert answer['positions'] == []                          # nothing half-made
    mixed, foreign, beyond, rotated = ask(
        move_group, {'position': REACHABLE, 'joint_goal': {'joint1': 0.3}},
        {'joint_goal': {'finger': 0.01}}, {'joint_goal': {'joint1': 5.0}},
        {'position': REACHABLE, 'orientation': [0.0, 0.0, 0.0, 1.0],
         'tolerances': [math.pi, 0.1, 0.1]})
    assert {mixed['code'], foreign['code'], beyond['code'], rotated['code']} == {
        'INVALID_GOAL_CONSTRAINTS'}
    assert 'joint constraints beside a position or orientation' in mixed['message']
    assert "joint constraint on 'finger': this node plans the chain joint1" in foreign['message']
    assert beyond['message'].startswith('joint goal joint1 = 5 rad is outside its limits')
    assert 'free about the x or y axis' in rotated['message']
    assert node.has('planner_id is ignored')
    assert node.proc.poll() is None                               # still serving
    again, = ask(move_group, {'position': REACHABLE})
    assert again['code'] == 'SUCCESS'


def test_a_joint_goal_moves_the_joints_it_names_there_and_keeps_the_others(move_group) -> None:
    start = {'joint1': 0.2, 'joint2': -0.1, 'joint3': 0.0, 'joint4': 0.4, 'joint5': 0.0}
    answer, = ask(move_group, {'joint_goal': {'joint1': -0.5, 'joint3': 0.7, 'joint5': 0.3},
                               'start': start})
    assert answer['code'] == 'SUCCESS', answer
    assert answer['message'].startswith('reached the joint goal in 0.7000 s')     # 1 rad/s
    assert answer['positions'][0] == list(start.values())
    assert answer['positions'][-1] == [-0.5, -0.1, 0.7, 0.4, 0.3]
    assert answer['times'][-1] == pytest.approx(0.7)


def test_compute_fk_poses_links_and_a_pose_a_five_joint_arm_cannot_take_has_no_ik(
        move_group) -> None:
    node, env = move_group
    q = np.array([-0.4, 0.5, 0.9, 0.3, 0.2])
    tip = ARM.frames(q[None])[0, -1]
    state = dict(zip(ARM.joint_names, q.tolist()))
    rotated = tip[:3, :3] @ np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], dtype=float)
    fk, unknown, cannot = scene_steps(
        NS, env, {'fk': {'links': ['tool_link', 'base_link'], 'state': state}},
        {'fk': {'links': ['camera_link'], 'state': state}},
        {'ik': {'position': tip[:3, 3].tolist(), 'seed': state,
                'orientation': quaternions(rotated[None])[0].tolist()}})
    assert fk['code'] == 'SUCCESS' and fk['links'] == ['tool_link', 'base_link'], fk
    np.testing.assert_allclose(fk['poses'][0][:3], tip[:3, 3], atol=1e-9)
    turn = quaternions(tip[None, :3, :3])[0]
    assert abs(float(np.dot(fk['poses'][0][3:], turn))) == pytest.approx(1.0, abs=1e-9)
    assert fk['poses'][1] == [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]
    assert unknown['code'] == 'INVALID_LINK_NAME' and 'camera_link' in unknown['message']
    assert cannot['code'] == 'NO_IK_SOLUTION' and cannot['solution'] == {}, cannot
    assert 'rad from' in cannot['message']


def test_a_five_joint_arm_asked_a_pose_it_cannot_take_says_how_far(move_group) -> None:
    q = np.array([0.3, 0.4, -0.6, 0.5, 0.0])
    frame = ARM.frames(q[None])[0, -1]
    turned = frame[:3, :3] @ np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], dtype=float)
    answer, = ask(move_group, {'position': frame[:3, 3].tolist(), 'radius': 0.001,
                               'orientation': quaternions(turned[None])[0].tolist(),
                               'tolerances': [0.01, 0.01, 0.01]})
    assert answer['code'] == 'GOAL_CONSTRAINTS_VIOLATED', answer
    assert 'rad from' in answer['message']


def test_a_cartesian_path_is_refused_at_once(move_group) -> None:
    _, env = move_group
    script = ('import rclpy\n'
              'from moveit_msgs.srv import GetCartesianPath\n'
              'rclpy.init()\n'
              'node = rclpy.create_node("cartesian_client")\n'
              f'client = node.create_client(GetCartesianPath, "{NS}/compute_cartesian_path")\n'
              'assert client.wait_for_service(timeout_sec=30.0)\n'
              'future = client.call_async(GetCartesianPath.Request())\n'
              'rclpy.spin_until_future_complete(node, future, timeout_sec=30.0)\n'
              'code = future.result().error_code\n'
              'print(code.val, code.message)\n')
    done = subprocess.run([sys.executable, '-c', script], env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.startswith('-1 straight-line tool paths are not offered'), done.stdout


def test_without_moveit_msgs_the_node_refuses_to_start_with_how_to_get_it(
        start_node: Callable[..., NodeProcess], ros_env: dict[str, str]) -> None:
    loads = subprocess.run([sys.executable, '-c', 'import moveit_msgs'], env=ros_env,
                           capture_output=True, timeout=60)
    if loads.returncode == 0:
        pytest.skip('moveit_msgs loads in the test environment: nothing to refuse')
    node = start_node('-r', '__ns:=/moveit_absent', '-p', 'moveit_interfaces:=true',
                      ready=False, env=ros_env)
    node.wait_for('moveit_interfaces needs moveit_msgs, which does not load here')
    assert node.proc.wait(timeout=30) == 2


def test_pymoveit2_plans_position_and_approach_goals_through_the_node(move_group) -> None:
    _, env = move_group
    q = np.array([-0.4, 0.5, 0.9, 0.3, 0.0])
    goal = ARM.frames(q[None])[0, -1]
    start = [0.1, 0.0, 0.2, 0.0, 0.0]
    spec = {'namespace': NS, 'joints': list(ARM.joint_names), 'base': 'base_link',
            'tip': 'tool_link',
            'start': start, 'goals': [
                {'position': list(REACHABLE)},
                {'position': goal[:3, 3].tolist(),
                 'quat_xyzw': quaternions(goal[None, :3, :3])[0].tolist(),
                 'tolerance_orientation': [0.01, 0.01, math.pi]},
                {'position': list(OUT_OF_REACH)}]}
    done = subprocess.run([sys.executable, str(CLIENT.with_name('pymoveit2_client.py')),
                           json.dumps(spec)], env=env,
                          capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr[-3000:]
    point, approach, unreachable = map(json.loads, done.stdout.splitlines())
    for answer in (point, approach):
        assert answer['joint_names'] == list(ARM.joint_names)
        assert answer['positions'][0] == start and answer['times'][0] == 0.0
    assert np.linalg.norm(tool_at(point['positions'][-1]) - REACHABLE) <= 0.001 + 1e-9
    frame = ARM.frames(np.array([approach['positions'][-1]]))[0, -1]
    assert float((frame[:3, :3] @ ARM.tool_axis) @ goal[:3, 2]) >= math.cos(0.01) - 1e-9
    assert unreachable is None                                  # pymoveit2: no trajectory


def urdf_move_group(start_node: Callable[..., NodeProcess], env: dict[str, str], folder: Path,
                    published: Any, namespace: str) -> NodeProcess:
    """Run the node as move_group for a published arm from its URDF (parameters from a file)."""
    params = folder / 'params.yaml'
    srdf = (f'<robot name="arm"><group name="arm"><chain base_link="{published.base_link}" '
            f'tip_link="{published.tip_link}"/></group></robot>')
    params.write_text(yaml.safe_dump({'/**': {'ros__parameters': {
        'robot_description_semantic': srdf,
        'robot_description': published.urdf.read_text(encoding='utf-8'),
        'base_link': published.base_link, 'tip_link': published.tip_link,
        'moveit_interfaces': True, 'angular_velocity': 1.0,
        'min_planning_time': 60.0,                            # pymoveit2 allows 0.5 s
        'collision_check': False}}}), encoding='utf-8')       # its meshes are not installed
    node = start_node('-r', f'__ns:={namespace}', '-r', '__node:=move_group', '--params-file',
                      str(params), ready=False, env=env)
    node.wait_for(r'move_group\]: ready: ')
    return node


def pymoveit2_plans(published: Any, namespace: str, env: dict[str, str],
                    goals: list[dict[str, Any]]) -> list[Any]:
    """Plan ``goals`` (MoveIt2.plan's keywords) with pymoveit2 from the arm's q = 0, clipped."""
    arm = ArmModel.from_urdf(published.urdf, published.base_link, published.tip_link)
    spec = {'namespace': namespace, 'joints': list(arm.joint_names),
            'base': published.base_link, 'tip': published.tip_link,
            'start': np.clip(0.0, arm.lower, arm.upper).tolist(), 'goals': goals}
    done = subprocess.run([sys.executable, str(CLIENT.with_name('pymoveit2_client.py')),
                           json.dumps(spec)], env=env, capture_output=True, text=True,
                          timeout=180)
    assert done.returncode == 0, done.stderr[-3000:]
    return [json.loads(line) for line in done.stdout.splitlines()]


@pytest.fixture(scope='module')
def so101_move_group(start_node: Callable[..., NodeProcess], moveit_msgs_env: dict[str, str],
                     tmp_path_factory: pytest.TempPathFactory) -> Iterator[NodeProcess]:
    node = urdf_move_group(start_node, moveit_msgs_env, tmp_path_factory.mktemp('so101'),
                           SO101, f'{NS}_so101')
    yield node
    assert node.stop() == 0, node.output


def test_pymoveit2_picks_from_above_with_the_so101(so101_move_group, moveit_msgs_env) -> None:
    arm = ArmModel.from_urdf(SO101.urdf, SO101.base_link, SO101.tip_link)
    goal = arm.frames(np.array([[0.3, 0.5, 0.4, 0.9, -0.2]]))[0, -1]
    joints = np.clip([-0.6, 0.3, 0.5, -0.4, 1.0], arm.lower, arm.upper).tolist()
    answer, configured = pymoveit2_plans(SO101, f'{NS}_so101', moveit_msgs_env, [
        {'position': goal[:3, 3].tolist(),
         'quat_xyzw': quaternions(goal[None, :3, :3])[0].tolist(),
         'tolerance_orientation': [0.01, 0.01, math.pi]},
        {'joint_positions': joints}])                           # move_to_configuration's
    assert answer is not None and configured is not None, so101_move_group.output
    assert configured['positions'][-1] == joints
    done = subprocess.run([sys.executable, str(CLIENT), f'{NS}_so101/plan_kinematic_path',
                           json.dumps([{'position': goal[:3, 3].tolist(),
                                        'group': 'manipulator'}])], env=moveit_msgs_env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-3000:]
    unknown = json.loads(done.stdout)
    assert unknown['code'] == 'INVALID_GROUP_NAME', unknown
    assert unknown['message'] == "group 'manipulator' is not in the SRDF (groups: arm)"
    frame = arm.frames(np.array([answer['positions'][-1]]))[0, -1]
    assert np.linalg.norm(frame[:3, 3] - goal[:3, 3]) <= 0.001 + 1e-9
    assert float((frame[:3, :3] @ arm.tool_axis) @ goal[:3, 2]) >= math.cos(0.01) - 1e-9


def test_pymoveit2_plans_full_poses_for_the_panda(start_node, moveit_msgs_env,
                                                  tmp_path) -> None:
    node = urdf_move_group(start_node, moveit_msgs_env, tmp_path, PANDA, f'{NS}_panda')
    arm = ArmModel.from_urdf(PANDA.urdf, PANDA.base_link, PANDA.tip_link)
    rng = np.random.default_rng(49)
    frames = arm.frames(rng.uniform(arm.lower, arm.upper, size=(3, arm.n_joints)))[:, -1]
    answers = pymoveit2_plans(PANDA, f'{NS}_panda', moveit_msgs_env, [
        {'position': f[:3, 3].tolist(), 'quat_xyzw': quaternions(f[None, :3, :3])[0].tolist()}
        for f in frames])                                   # pymoveit2's 1 mm and 0.001 rad
    seed = {**dict(zip(arm.joint_names, np.clip(0.0, arm.lower, arm.upper).tolist())),
            'panda_finger_joint1': 0.02}
    ik, = scene_steps(f'{NS}_panda', moveit_msgs_env, {'ik': {
        'position': frames[0][:3, 3].tolist(), 'seed': seed,
        'orientation': quaternions(frames[0][None, :3, :3])[0].tolist()}})
    assert node.stop() == 0, node.output
    assert node.has('allowed_planning_time is raised to min_planning_time; said once')
    for goal, answer in zip(frames, answers):
        assert answer is not None, node.output
        end = arm.frames(np.array([answer['positions'][-1]]))[0, -1]
        assert np.linalg.norm(end[:3, 3] - goal[:3, 3]) <= 0.001 + 1e-9
        turn = (np.trace(goal[:3, :3].T @ end[:3, :3]) - 1) / 2
        assert turn >= math.cos(0.001) - 1e-9
    assert ik['code'] == 'SUCCESS', ik                          # the node's 1e-6 m and rad
    assert ik['solution']['panda_finger_joint1'] == 0.02        # the seed's other joints
    end = arm.frames(np.array([[ik['solution'][n] for n in arm.joint_names]]))[0, -1]
    assert np.linalg.norm(end[:3, 3] - frames[0][:3, 3]) <= 1e-6 + 1e-9
    assert (np.trace(frames[0][:3, :3].T @ end[:3, :3]) - 1) / 2 >= math.cos(1e-6) - 1e-9


def test_the_bench_measures_round_trips_beside_the_plan(moveit_msgs_env) -> None:
    done = subprocess.run([sys.executable, '-m', 'trajplan_ros.tools.bench_moveit', '--calls',
                           '3'], env=moveit_msgs_env, capture_output=True, text=True,
                          timeout=300, cwd=Path(__file__).resolve().parents[1])
    assert done.returncode in (0, 1), done.stderr[-3000:]      # 1: the target not met here
    assert 'plan_kinematic_path: 3 requests (the paper arm, a sphere of 0.001 m), 3 SUCCESS' \
        in done.stdout, done.stdout
    assert 'target: median overhead <= 2 x the empty call' in done.stdout
    done = subprocess.run([sys.executable, '-m', 'trajplan_ros.tools.bench_moveit', '--quality',
                           '--calls', '2', '--radius', '0.01'], env=moveit_msgs_env,
                          capture_output=True, text=True, timeout=300,
                          cwd=Path(__file__).resolve().parents[1])
    assert done.returncode in (0, 1), done.stderr[-3000:]
    assert ('plan_kinematic_path: 2 held-out region goals (the paper arm, spheres of 0.01 m), '
            '2 SUCCESS') in done.stdout, done.stdout
    assert 'target: >= 99 % within 0.1 %' in done.stdout


@pytest.fixture(scope='module')
def executing(start_node: Callable[..., NodeProcess], moveit_msgs_env: dict[str, str],
              control_msgs_env: dict[str, str]) -> Iterator[tuple[NodeProcess, dict]]:
    """Run move_group with execute_trajectory and the demo controller it executes through."""
    env = {**control_msgs_env, **moveit_msgs_env}
    controller = start_node('-r', f'__ns:={NS}_exec', ready=False, env=env,
                            executable='demo_controller')
    controller.wait_for(r'demo_controller\]: ready: ')
    node = start_node('-r', f'__ns:={NS}_exec', '-r', '__node:=move_group', '-p',
                      'moveit_interfaces:=true', ready=False, env=env)     # 0.2 rad/s: seconds
    node.wait_for(r"move_group\]: MoveIt's interfaces ready: plan_kinematic_path, .*"
                  'execute_trajectory, move_action')
    node.wait_for(r'move_group\]: ready: ')
    yield node, env
    assert node.stop() == 0, node.output
    assert controller.stop() == 0, controller.output


def test_a_planned_trajectory_is_executed_cancelled_or_refused(executing, peer) -> None:
    node, env = executing
    specs = [{'position': list(REACHABLE), 'execute': 'run'},
             {'position': [0.2, -0.15, 0.1], 'execute': 'cancel'},     # 1.5 rad of joint1
             {'position': list(REACHABLE), 'execute': 'foreign'},
             {'joint_goal': {'joint1': 1.5}, 'execute': 'stop'}]
    done = subprocess.run([sys.executable, str(CLIENT), f'{NS}_exec/plan_kinematic_path',
                           json.dumps(specs)], env=env, capture_output=True, text=True,
                          timeout=180)
    assert done.returncode == 0, done.stderr[-3000:]
    ran, cancelled, foreign, stopped = map(json.loads, done.stdout.splitlines())
    assert cancelled['code'] == 'SUCCESS', node.output
    assert ran['code'] == 'SUCCESS' and ran['execution']['code'] == 'SUCCESS', (
        ran['execution'], node.output)
    assert ran['execution']['status'] == 4                      # SUCCEEDED
    assert cancelled['execution']['code'] == 'PREEMPTED', cancelled
    assert cancelled['execution']['status'] == 5                # CANCELED
    assert foreign['execution']['code'] == 'INVALID_MOTION_PLAN', foreign
    assert 'executes the chain' in foreign['execution']['message']
    assert node.has(r'execute_trajectory #\d+ .*execution: executed: reached the goal')
    assert stopped['execution']['code'] == 'PREEMPTED', stopped
    assert stopped['execution']['status'] == 6                  # ABORTED: not a cancel
    assert node.has('trajectory_execution_event stop: 1 executions cancelled')
    told, = peer.set_parameters(f'{NS}_exec/demo_controller', [Parameter('fail',
                                                                         value='reject')])
    assert told.successful, told.reason
    done = subprocess.run([sys.executable, str(CLIENT), f'{NS}_exec/plan_kinematic_path',
                           json.dumps([{'joint_goal': {'joint1': 0.0}, 'execute': 'run'}])],
                          env=env, capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr[-3000:]
    rejected = json.loads(done.stdout)
    assert rejected['execution']['code'] == 'CONTROL_FAILED', rejected
    assert rejected['execution']['status'] == 6 and 'rejected' in rejected['execution']['message']
    told, = peer.set_parameters(f'{NS}_exec/demo_controller', [Parameter('fail', value='')])
    assert told.successful, told.reason


def test_move_action_plans_then_executes_unless_plan_only(executing) -> None:
    node, env = executing
    specs = [{'position': list(REACHABLE), 'move': 'plan_only'},
             {'position': list(REACHABLE), 'move': 'run'},
             {'position': list(OUT_OF_REACH), 'move': 'run'}]
    done = subprocess.run([sys.executable, str(CLIENT), f'{NS}_exec/plan_kinematic_path',
                           json.dumps(specs)], env=env, capture_output=True, text=True,
                          timeout=180)
    assert done.returncode == 0, done.stderr[-3000:]
    planned, moved, unreachable = map(json.loads, done.stdout.splitlines())
    assert planned['code'] == moved['code'] == 'SUCCESS', node.output
    assert planned['status'] == moved['status'] == 4                # SUCCEEDED
    assert planned['states'] == ['PLANNING', 'IDLE'] and planned['executed'] == 0
    assert moved['states'] == ['PLANNING', 'MONITOR', 'IDLE']
    assert moved['executed'] == len(moved['positions']) > 1
    assert np.linalg.norm(tool_at(moved['positions'][-1]) - REACHABLE) <= 0.001 + 1e-9
    assert unreachable['code'] == 'NO_IK_SOLUTION' and unreachable['status'] == 6
    assert unreachable['positions'] == []


def scene_steps(node_ns: str, env: dict[str, str], *steps: dict[str, Any]) -> list[Any]:
    """Run ``moveit_scene_client.py``'s steps against move_group in ``node_ns``."""
    done = subprocess.run([sys.executable, str(CLIENT.with_name('moveit_scene_client.py')),
                           node_ns, json.dumps(steps)], env=env, capture_output=True,
                          text=True, timeout=180)
    assert done.returncode == 0, done.stderr[-3000:]
    return [json.loads(line) for line in done.stdout.splitlines()]


def test_world_objects_are_added_moved_appended_and_removed_and_plans_avoid_them(
        start_node, moveit_msgs_env) -> None:
    ns = f'{NS}_scene'
    node = start_node('-r', f'__ns:={ns}', '-r', '__node:=move_group', '-p',
                      'moveit_interfaces:=true', '-p', 'angular_velocity:=1.0', ready=False,
                      env=moveit_msgs_env)
    node.wait_for(r'move_group\]: ready: ')
    assert node.has(r'collision check: \d+ link pairs')           # on by default here
    crate = {'id': 'crate', 'frame': 'base_link', 'pose': list(REACHABLE),
             'primitives': [['BOX', [0.05, 0.05, 0.05], [0.0, 0.0, 0.0]]]}
    away = [0.3, -0.3, 0.05]
    tetrahedron = [[[-0.03, -0.03, -0.03], [0.06, 0.0, 0.0], [0.0, 0.06, 0.0],
                    [0.0, 0.0, 0.06]], [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]]
    free, = scene_steps(ns, moveit_msgs_env, {'plan': {'position': REACHABLE}})
    there = dict(zip(ARM.joint_names, free['last']))
    (added, inside, joint, bad, foreign, moved, after_move, appended, scene, twice, mesh,
     in_mesh, post, blocked_start, acm, cleared, removed, again) = scene_steps(
        ns, moveit_msgs_env,
        {'publish': crate, 'expect': ['crate']},
        {'plan': {'position': REACHABLE}},
        {'plan': {'joint_goal': there}},
        {'publish': {'id': 'empty'}, 'expect': ['crate']},
        {'publish': {**crate, 'id': 'far', 'frame': 'camera_link'}, 'expect': ['crate']},
        {'publish': {'id': 'crate', 'operation': 'MOVE', 'frame': 'base_link', 'pose': away},
         'expect': ['crate']},
        {'plan': {'position': REACHABLE}},
        {'publish': {'id': 'crate', 'operation': 'APPEND', 'frame': 'base_link',
                     'pose': away, 'primitives': [['CONE', [0.1, 0.03], [0.0, 0.0, 0.1]],
                                                  ['CYLINDER', [0.1, 0.02], [0.1, 0, 0]]]},
         'expect': ['crate']},
        {'scene': True},
        {'publish': {**crate, 'id': 'crate#1'}, 'expect': ['crate']},   # a shape's id twice
        {'publish': {'id': 'part', 'frame': 'base_link', 'pose': list(REACHABLE),
                     'mesh': tetrahedron}, 'expect': ['crate', 'part']},
        {'plan': {'position': REACHABLE}},
        {'publish': {'id': 'post', 'frame': 'base_link', 'pose': [0.0, 0.0, 0.1],
                     'primitives': [['BOX', [0.03, 0.03, 0.03], [0.0, 0.0, 0.0]]]},
         'expect': ['crate', 'part', 'post']},
        {'plan': {'position': REACHABLE, 'start': {n: 0.0 for n in ARM.joint_names}}},
        {'apply': {'acm': True}},
        {'apply': {'is_diff': False, 'objects': [crate]}},
        {'publish': {'id': '', 'operation': 'REMOVE'}, 'expect': []},
        {'plan': {'position': REACHABLE}})
    assert node.stop() == 0, node.output
    assert free['code'] == 'SUCCESS' and added['ids'] == ['crate'], (free, added)
    assert inside['code'] == 'GOAL_IN_COLLISION', inside
    assert "inside obstacle 'crate'" in inside['message']
    assert joint['code'] == 'GOAL_IN_COLLISION', joint
    assert joint['message'].startswith('the joint goal is in collision: ')
    assert 'crate' in joint['message']
    assert bad['ids'] == foreign['ids'] == ['crate']
    assert node.has('collision_object refused, scene kept: collision object .empty.: no '
                    'primitive or mesh')
    assert node.has('collision_object refused, scene kept: collision object .far.: .*'
                    'camera_link')
    assert moved['ids'] == ['crate'] and after_move['code'] == 'SUCCESS', after_move
    assert scene['objects'] == [{'id': 'crate', 'frame': 'base_link', 'primitives': [1, 4, 3],
                                 'meshes': 0}]
    assert scene['joints'] == list(ARM.joint_names)
    assert twice['ids'] == ['crate']
    assert node.has(r'collision_object refused, scene kept: obstacle ids must be unique: '
                    r".'crate#1'. repeat")
    assert mesh['ids'] == ['crate', 'part']
    assert in_mesh['code'] == 'GOAL_IN_COLLISION' and 'part' in in_mesh['message'], in_mesh
    assert blocked_start['code'] == 'START_STATE_IN_COLLISION', blocked_start
    assert "the start is in collision: link2 with 'post'" in blocked_start['message']
    assert acm == {'success': False} and cleared == {'success': True}
    assert node.has('apply_planning_scene refused, scene kept: collision-matrix edits')
    assert removed['ids'] == [] and again['code'] == 'SUCCESS', again


def test_the_readme_pymoveit2_block_runs_as_pasted(start_node, moveit_msgs_env) -> None:
    readme = (Path(__file__).resolve().parents[1] / 'README.md').read_text(encoding='utf-8')
    tag = 'needs moveit_msgs built (test_node_moveit runs this block against the node)'
    block = readme.split(tag, 1)[1].split('```python\n', 1)[1].split('```', 1)[0]
    ns = f'{NS}_readme'
    node = start_node('-r', f'__ns:={ns}', '-r', '__node:=move_group', '-p',
                      'moveit_interfaces:=true', '-p', 'min_planning_time:=30.0', ready=False,
                      env=moveit_msgs_env)
    node.wait_for(r'move_group\]: ready: ')
    done = subprocess.run([sys.executable, '-c', block, '--ros-args', '-r', f'__ns:={ns}'],
                          env=moveit_msgs_env, capture_output=True, text=True, timeout=120)
    assert node.stop() == 0, node.output
    assert done.returncode == 0, done.stderr[-3000:]
    points, seconds = re.fullmatch(r'(\d+) points, (\d+) s\n', done.stdout).groups()
    assert int(points) > 2, done.stdout
