# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The planner node as a child process of this one: how to start it, its environment, its log.

Used by ``trajplan demo``, the node benchmark and the integration tests. Nothing here imports
rclpy: the child process is the node; talking to it over DDS is ``ros_client``'s job.
"""
from __future__ import annotations

import os
from pathlib import Path
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from typing import Callable, Mapping, Sequence


__all__ = ['COMPILE_BOUND_S', 'TIMEOUT_S', 'PlannerProcess', 'planner_command',
           'ros_environment', 'rss_mb', 'wait_until']

#: Liveness bound (s) for anything a client waits on by default: discovery, an answer.
TIMEOUT_S = 60.0
#: Liveness bound (s) on the compile of a first start, which the node announces in its log.
COMPILE_BOUND_S = 900.0


def wait_until(predicate: Callable[[], bool], timeout: float = TIMEOUT_S,
               what: str = 'a condition') -> None:
    """Poll ``predicate`` every 20 ms until it holds; raise TimeoutError after ``timeout`` s."""
    tick = threading.Event()
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise TimeoutError(f'timed out after {timeout:g} s waiting for {what}')
        tick.wait(0.02)


def rss_mb(pid: int, field: str = 'VmRSS') -> float:
    """Return the resident memory of process ``pid``, MB (``VmHWM``: its peak so far)."""
    with open(f'/proc/{pid}/status', encoding='ascii') as status:
        for line in status:
            if line.startswith(field + ':'):
                return int(line.split()[1]) / 1024
    return float('nan')


def planner_command(executable: str = 'planner_node') -> list[str]:
    """
    Return the command that starts the node (or the package's other ``executable``).

    That is the executable beside this Python (a venv's bin), else on PATH, else
    ``python -m trajplan_ros.ros.<module>`` (a source checkout).
    """
    beside = Path(sys.executable).with_name(executable)
    if beside.is_file() and os.access(beside, os.X_OK):
        return [str(beside)]
    found = shutil.which(executable)
    module = {'planner_node': 'node'}.get(executable, executable)
    return [found] if found else [sys.executable, '-m', f'trajplan_ros.ros.{module}']


def ros_environment(base: Mapping[str, str] | None = None) -> dict[str, str]:
    """
    Return ``base`` (default os.environ) set up for a node of this process's own.

    That is a DDS domain of this process's own (1..100, from the pid), localhost-only
    discovery, and this Python's prefix on AMENT_PREFIX_PATH (where the pip-installed ROS 2
    packages register themselves).
    """
    env = dict(os.environ if base is None else base)
    env['ROS_DOMAIN_ID'] = str(1 + os.getpid() % 100)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    prefixes = [p for p in env.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]
    if sys.prefix not in prefixes:
        env['AMENT_PREFIX_PATH'] = os.pathsep.join([*prefixes, sys.prefix])
    env['PYTHONUNBUFFERED'] = '1'
    return env


class PlannerProcess:
    """``planner_node`` as a child process; its log lines are collected as they come."""

    def __init__(self, ros_args: Sequence[str] = (), env: Mapping[str, str] | None = None,
                 argv: Sequence[str] | None = None) -> None:
        """Run ``argv`` (default: ``planner_command()``) with ``--ros-args ros_args``."""
        argv = list(argv or planner_command()) + (['--ros-args', *ros_args] if ros_args else [])
        self.argv = argv
        self.proc = subprocess.Popen(argv, env=dict(env or ros_environment()),
                                     stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, text=True)
        self.lines: list[str] = []
        self._eof = False
        self._cond = threading.Condition()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    @property
    def pid(self) -> int:
        return self.proc.pid

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            with self._cond:
                self.lines.append(line.rstrip('\n'))
                self._cond.notify_all()
        with self._cond:
            self._eof = True
            self._cond.notify_all()

    def wait_for(self, pattern: str, timeout: float, after: int = 0) -> re.Match[str] | None:
        """Return the first log line from ``after`` on matching ``pattern``; None on timeout."""
        regex = re.compile(pattern)
        found: list[re.Match[str]] = []

        def scan() -> bool:
            found[:] = [m for m in map(regex.search, self.lines[after:]) if m][:1]
            return bool(found) or self._eof

        with self._cond:
            self._cond.wait_for(scan, timeout=timeout)
        return found[0] if found else None

    def matches(self, pattern: str) -> list[re.Match[str]]:
        """Every log line so far that matches ``pattern``."""
        regex = re.compile(pattern)
        with self._cond:
            return [m for m in map(regex.search, self.lines) if m]

    def stop(self, sig: int = signal.SIGINT, timeout: float = 5.0) -> int:
        """``sig`` (SIGINT) by PID, SIGKILL after ``timeout`` s; the exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._reader.join(timeout=timeout)
        return self.proc.returncode
