# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The node under test: its colcon install, its process, and checks of what it logs and publishes.

Shared by the DDS and system tests (``conftest.py`` gives the fixtures). Importing this module
needs no ROS 2: message types appear in annotations only.
"""
from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path
import re
import signal
import sys
import time
from typing import Mapping, TYPE_CHECKING

import numpy as np
import pytest
from trajplan_ros import paper_arm
from trajplan_ros.tools.node_process import PlannerProcess, TIMEOUT_S, wait_until

if TYPE_CHECKING:
    from trajectory_msgs.msg import JointTrajectory

__all__ = ['ARM', 'check_servo_trajectory', 'fmt', 'HOPELESS_GOAL', 'Install', 'LIVENESS_S',
           'NodeProcess', 'OMEGA', 'PACKAGE', 'REPO', 'seconds', 'started_from', 'trajectory_to',
           'wait_until']

REPO = Path(__file__).resolve().parents[1]
PACKAGE = 'trajplan_ros'
#: Liveness bound for anything the tests wait on (discovery, a plan, a build step).
LIVENESS_S = TIMEOUT_S


@dataclass(frozen=True)
class Install:
    """A colcon install of the package (isolated layout: one prefix per package)."""

    prefix: Path

    @property
    def executable(self) -> Path:
        return self.prefix / 'lib' / PACKAGE / 'planner_node'

    def env(self, base: Mapping[str, str]) -> dict[str, str]:
        """Return ``base`` plus what ``source install/setup.bash`` adds (venv as underlay)."""
        python = f'python{sys.version_info.major}.{sys.version_info.minor}'
        site = self.prefix / 'lib' / python / 'site-packages'
        env = dict(base)
        env['PYTHONPATH'] = os.pathsep.join(filter(None, [str(site), base.get('PYTHONPATH')]))
        env['AMENT_PREFIX_PATH'] = os.pathsep.join([str(self.prefix), sys.prefix])
        env['PYTHONUNBUFFERED'] = '1'
        return env


class NodeProcess(PlannerProcess):
    """A planner_node subprocess (``trajplan_ros.tools.demo.PlannerProcess``) with test helpers."""

    def __init__(self, argv: list[str], env: Mapping[str, str]) -> None:
        super().__init__(env=env, argv=argv)

    @property
    def output(self) -> str:
        with self._cond:
            return '\n'.join(self.lines)

    def mark(self) -> int:
        """Return a position in the output; ``wait_for(..., after=mark)`` looks after it."""
        with self._cond:
            return len(self.lines)

    def has(self, pattern: str, after: int = 0) -> bool:
        """Whether a line at or after ``after`` matches ``pattern`` (a regex) by now."""
        regex = re.compile(pattern)
        with self._cond:
            return any(regex.search(line) for line in self.lines[after:])

    def wait_for(self, pattern: str, after: int = 0, timeout: float = LIVENESS_S) -> re.Match[str]:
        """Return the first line at or after ``after`` matching ``pattern`` (a regex), or fail."""
        found = super().wait_for(pattern, timeout, after)
        if found is None:
            state = 'exited' if self.proc.poll() is not None else 'still running'
            pytest.fail(f'no line matching {pattern!r} within {timeout:.0f} s (node {state}); '
                        'output:\n' + '\n'.join(self.lines[-40:]))
        return found

    def stop(self, sig: int = signal.SIGINT, timeout: float = 10.0) -> int:
        return super().stop(sig, timeout)


ARM = paper_arm()
OMEGA = 0.2                                       # the node's default angular_velocity
HOPELESS_GOAL = (0.05, -0.05, -0.25)              # inside the reach sphere, never reached


def fmt(xyz: tuple[float, ...]) -> str:
    """Write a point as the node does in its log lines, as a regex."""
    return re.escape('(' + ', '.join(f'{v:.6g}' for v in xyz) + ')')


def started_from(node: NodeProcess, kind: str, goal: tuple[float, float, float],
                 after: int) -> tuple[str, np.ndarray]:
    """Return the label and start angles of the plan the node logged for ``goal``."""
    sources = r'(?: \[[^]]*\])?'                  # where the joints came from, if not one place
    m = node.wait_for(rf'\]: ({kind} #\d+) {fmt(goal)} m from q = \(([^)]*)\) rad{sources}: ',
                      after)
    return m.group(1), np.array([float(v) for v in m.group(2).split(',')])


def trajectory_to(box, goal: tuple[float, float, float], arm=ARM, tol: float = 1e-5):
    """
    Return the next trajectory in ``box`` that ends at ``goal``.

    One from an earlier plan may still be on its way: the node publishes just after answering.
    """
    deadline = time.monotonic() + LIVENESS_S
    while True:
        msg = box.get(timeout=max(0.0, deadline - time.monotonic()))
        if len(msg.joint_names) == arm.n_joints:
            end = np.array(msg.points[-1].positions)
            if np.linalg.norm(arm.tool(end[None, :])[0][0] - goal) <= tol:
                return msg


def seconds(duration) -> float:
    return duration.sec + 1e-9 * duration.nanosec


def check_servo_trajectory(msg: JointTrajectory, start: np.ndarray, omega: float = OMEGA,
                           names: tuple[str, ...] = ARM.joint_names) -> np.ndarray:
    """Assert the rules of a published trajectory; return its final joint angles."""
    assert tuple(msg.joint_names) == tuple(names)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (0, 0)       # start now
    assert msg.points
    t = np.array([seconds(p.time_from_start) for p in msg.points])
    q = np.array([p.positions for p in msg.points])
    assert q.shape == (t.size, len(names))
    # positions only, so that joint_trajectory_controller interpolates linearly (exact here)
    assert not any(len(p.velocities) or len(p.accelerations) for p in msg.points)
    assert t[0] > 0 and np.all(np.diff(t) > 0)                                # strictly increasing
    # fixed angular velocity between points: no joint turns faster than omega; it never turns
    # back and, once stopped, stays stopped (the segment of a joint's arrival may be slower)
    v = np.diff(q, axis=0) / np.diff(t)[:, None]
    assert np.all(np.abs(v) <= omega * (1 + 1e-9))
    for j in range(len(names)):
        moving = np.abs(v[:, j]) > omega / 2
        assert np.all(np.diff(moving.astype(int)) <= 0), f'joint {names[j]} restarts'
        assert len(set(np.sign(v[moving, j]))) <= 1, f'joint {names[j]} turns back'
    # the first point is omega * t1 from the start (or at the start); ``start`` comes from a
    # log line with 6 significant digits, hence the tolerance
    first = np.abs(q[0] - start)
    assert np.all(np.isclose(first, omega * t[0], atol=1e-5) | np.isclose(first, 0, atol=1e-5))
    # eq. (10): the motion lasts max |goal - start| / omega
    assert t[-1] == pytest.approx(np.max(np.abs(q[-1] - start)) / omega, abs=1e-4)
    return q[-1]


def rotation(quat) -> np.ndarray:
    x, y, z, w = quat.x, quat.y, quat.z, quat.w
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
