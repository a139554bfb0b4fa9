# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
``trajplan demo`` end to end.

It starts planner_node, plans the paper's example through the service, prints the plan and
the trajectory, and stops the node it started.
"""
from __future__ import annotations

import os
import re
import subprocess
import sys

from node_under_test import Install, LIVENESS_S
import pytest
from trajplan_ros.tools.node_process import COMPILE_BOUND_S

pytestmark = pytest.mark.system


def test_demo_plans_the_paper_example_through_the_node(colcon_install: Install, tmp_path) -> None:
    env = colcon_install.env(os.environ)
    # as after `source install/setup.bash`: planner_node is found on the PATH
    env['PATH'] = os.pathsep.join([str(colcon_install.executable.parent), env.get('PATH', '')])
    # a run of only this test compiles the kernels: the demo then waits as long as that takes
    done = subprocess.run([sys.executable, '-m', 'trajplan_ros.tools.cli', 'demo'], cwd=tmp_path,
                          env=env, capture_output=True, text=True,
                          timeout=COMPILE_BOUND_S + 3 * LIVENESS_S)
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
