# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
``trajplan demo`` end to end.

It starts planner_node, plans the paper's example through the service, prints the plan and
the trajectory, and stops the node it started; where control_msgs loads, it executes two goals
through demo_controller, the second from where the first ended.
"""
from __future__ import annotations

import os
from pathlib import Path
import re
import subprocess
import sys
from typing import Mapping

from node_under_test import Install, LIVENESS_S
import numpy as np
import pytest
from trajplan_ros import plan
from trajplan_ros.tools.bench.cases import PAPER_TARGET
from trajplan_ros.tools.node_process import COMPILE_BOUND_S

pytestmark = pytest.mark.system


def run_demo(install: Install, base: Mapping[str, str],
             cwd: Path) -> subprocess.CompletedProcess:
    """Run ``trajplan demo`` with ``base`` as ``source install/setup.bash`` would leave it."""
    env = install.env(base)
    # as after `source install/setup.bash`: planner_node is found on the PATH
    env['PATH'] = os.pathsep.join([str(install.executable.parent), env.get('PATH', '')])
    # a run of only this test compiles the kernels: the demo then waits as long as that takes
    return subprocess.run([sys.executable, '-m', 'trajplan_ros.tools.cli', 'demo'], cwd=cwd,
                          env=env, capture_output=True, text=True,
                          timeout=COMPILE_BOUND_S + 3 * LIVENESS_S)


def test_demo_plans_the_paper_example_through_the_node(colcon_install: Install, tmp_path) -> None:
    done = run_demo(colcon_install, os.environ, tmp_path)
    out = done.stdout
    assert done.returncode == 0, out + done.stderr
    # the demo prefers planner_node beside this Python (a pip venv), else the one on the PATH
    assert re.search(r'^started \S*/planner_node \(pid \d+\), ROS_DOMAIN_ID=\d+, '
                     r'localhost discovery',
                     out, re.M), out
    assert re.search(r'planned joint angles \[rad\]: joint1=\S+ +joint2=\S+ +joint3=\S+ '
                     r'+joint4=\S+ '
                     r'+joint5=\+0\.000000', out), out
    assert re.search(r'motion time: \d+\.\d{4} s', out)
    error = float(re.search(r'position error: (\S+) m', out).group(1))
    assert error <= 1e-6                                     # the node's default tolerance
    assert re.search(r'JointTrajectory on joint_trajectory: \d+ points, joints joint1, joint2, '
                     r'joint3, joint4, joint5; header.stamp 0.000000000 \(start now\)', out)
    assert 'points carry positions' in out
    pid = int(re.search(r'stopped planner_node \(pid (\d+), exit code 0\)', out).group(1))
    assert not os.path.exists(f'/proc/{pid}'), 'the demo left its node running'
    assert 'Traceback' not in out + done.stderr


def test_demo_closes_the_loop_where_control_msgs_loads(
        colcon_install: Install, control_msgs_env: dict[str, str], tmp_path) -> None:
    done = run_demo(colcon_install, control_msgs_env, tmp_path)
    out = done.stdout
    assert done.returncode == 0, out + done.stderr
    assert re.search(r'^started \S*/demo_controller \(pid \d+\)', out, re.M), out
    assert re.search(r'^started \S*/planner_node --ros-args -p execution:=action', out, re.M)
    assert out.count('execution: accepted') == 2 and out.count('executed: reached the goal') == 2
    # the second plan starts where the first motion ended, as joint_states told the node
    second = re.search(r'service call #2 \S+ \S+ \S+ m from q = \(([^)]*)\)', out).group(1)
    first_goal = plan(tuple(PAPER_TARGET), seed=0).joint_goal
    assert np.allclose([float(q) for q in second.split(',')], first_goal, atol=1e-5), out
    ends = [re.search(r'stopped (\S+) \(pid (\d+), exit code 0\)', line)
            for line in out.splitlines() if line.startswith('stopped ')]
    assert [m.group(1) for m in ends if m] == ['planner_node', 'demo_controller'], out
    assert not [m for m in ends if os.path.exists(f'/proc/{m.group(2)}')]
