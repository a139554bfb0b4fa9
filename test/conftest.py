"""
Shared fixtures for the ROS 2 integration tests (test_node*.py).

Importing this file needs no ROS 2: rclpy and the interface packages are imported inside the
fixtures, so the core's tests run where ROS 2 is absent. The ROS tests themselves import rclpy
and fail loudly without it (nothing is skipped).

The node under test runs as its own process, the way ``ros2 run trajplan_ros planner_node``
runs it: the executable installed by ``colcon build`` (built once per session into a temporary
directory), with the environment ``source install/setup.bash`` would give it. The test process
and every node share one DDS domain chosen from the pid, with discovery kept on localhost.
"""
from __future__ import annotations

import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping

import pytest

from trajplan_ros.tools.demo import PlannerProcess

REPO = Path(__file__).resolve().parents[1]
PACKAGE = 'trajplan_ros'
#: Liveness bound for anything the tests wait on (discovery, a plan, a build step).
LIVENESS_S = 60.0


def wait_until(predicate: Callable[[], bool], timeout: float = LIVENESS_S,
               what: str = 'condition') -> None:
    """Poll ``predicate`` every 20 ms until it holds; fail after ``timeout`` seconds."""
    tick = threading.Event()
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            pytest.fail(f'timed out after {timeout:.0f} s waiting for {what}')
        tick.wait(0.02)


# --- environment and the colcon install ---------------------------------------------------------

@pytest.fixture(scope='session')
def ros_env() -> Iterator[dict[str, str]]:
    """Isolate this test run on DDS: a domain from the pid (1..100), localhost discovery."""
    patch = pytest.MonkeyPatch()
    patch.setenv('ROS_DOMAIN_ID', str(1 + os.getpid() % 100))
    patch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    yield dict(os.environ)
    patch.undo()


@dataclass(frozen=True)
class Install:
    """A colcon install of the package (isolated layout: one prefix per package)."""

    prefix: Path

    @property
    def executable(self) -> Path:
        return self.prefix / 'lib' / PACKAGE / 'planner_node'

    def env(self, base: Mapping[str, str]) -> dict[str, str]:
        """``base`` plus what ``source install/setup.bash`` adds (the venv is the underlay)."""
        site = self.prefix / 'lib' / f'python{sys.version_info.major}.{sys.version_info.minor}' / 'site-packages'
        env = dict(base)
        env['PYTHONPATH'] = os.pathsep.join(filter(None, [str(site), base.get('PYTHONPATH')]))
        env['AMENT_PREFIX_PATH'] = os.pathsep.join([str(self.prefix), sys.prefix])
        env['PYTHONUNBUFFERED'] = '1'
        return env


@pytest.fixture(scope='session')
def colcon_install(tmp_path_factory: pytest.TempPathFactory, ros_env: dict[str, str]) -> Install:
    """``colcon build`` of this repository into a temporary directory, once per session."""
    root = tmp_path_factory.mktemp('colcon')
    cmd = [sys.executable, '-m', 'colcon', '--log-base', str(root / 'log'), 'build',
           '--base-paths', str(REPO), '--build-base', str(root / 'build'),
           '--install-base', str(root / 'install')]
    done = subprocess.run(cmd, cwd=root, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, f'colcon build failed:\n{done.stdout}\n{done.stderr}'
    return Install(root / 'install' / PACKAGE)


# --- the node process ---------------------------------------------------------------------------

class NodeProcess(PlannerProcess):
    """A planner_node subprocess (``trajplan_ros.tools.demo.PlannerProcess``) with test helpers."""

    def __init__(self, argv: list[str], env: Mapping[str, str]) -> None:
        super().__init__(env=env, argv=argv)

    @property
    def output(self) -> str:
        with self._cond:
            return '\n'.join(self.lines)

    def mark(self) -> int:
        """A position in the output; ``wait_for(..., after=mark)`` looks only at later lines."""
        with self._cond:
            return len(self.lines)

    def has(self, pattern: str, after: int = 0) -> bool:
        """Whether a line at or after ``after`` matches ``pattern`` (a regex) by now."""
        regex = re.compile(pattern)
        with self._cond:
            return any(regex.search(line) for line in self.lines[after:])

    def wait_for(self, pattern: str, after: int = 0, timeout: float = LIVENESS_S) -> re.Match[str]:
        """The first line at or after ``after`` that ``pattern`` (a regex) matches; else fail."""
        found = super().wait_for(pattern, timeout, after)
        if found is None:
            state = 'exited' if self.proc.poll() is not None else 'still running'
            pytest.fail(f'no line matching {pattern!r} within {timeout:.0f} s (node {state}); '
                        'output:\n' + '\n'.join(self.lines[-40:]))
        return found

    def stop(self, sig: int = signal.SIGINT, timeout: float = 10.0) -> int:
        return super().stop(sig, timeout)


@pytest.fixture(scope='session')
def start_node(colcon_install: Install, ros_env: dict[str, str]) -> Iterator[Callable[..., NodeProcess]]:
    """
    Factory: ``start_node(*ros_args, ready=True)`` runs the installed planner_node.

    With ``ready`` it waits for the node's "ready" log line. Every node started is stopped
    (SIGINT, then SIGKILL) at the end of the session if a test has not stopped it.
    """
    started: list[NodeProcess] = []

    def start(*ros_args: str, ready: bool = True) -> NodeProcess:
        argv = [str(colcon_install.executable)] + (['--ros-args', *ros_args] if ros_args else [])
        node = NodeProcess(argv, colcon_install.env(os.environ))
        started.append(node)
        if ready:
            node.wait_for(r'trajplan\]: ready: ')
        return node

    yield start
    for node in started:
        node.stop()


# --- the test process's side of DDS -------------------------------------------------------------

class Peer:
    """A node of the test process, spun on a background thread, to talk to the planner."""

    def __init__(self) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self._rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node('trajplan_test_peer', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._spinner = threading.Thread(target=self.executor.spin, daemon=True)
        self._spinner.start()
        self._clients: dict[str, Any] = {}
        self._publishers: dict[str, Any] = {}
        self._inboxes: dict[str, tuple[Any, queue.Queue[Any]]] = {}

    def close(self) -> None:
        self.executor.shutdown()
        self._spinner.join(timeout=LIVENESS_S)
        self.node.destroy_node()
        self._rclpy.try_shutdown(context=self.context)

    # services

    def client(self, srv_type: Any, name: str) -> Any:
        if name not in self._clients:
            self._clients[name] = self.node.create_client(srv_type, name)
        client = self._clients[name]
        assert client.wait_for_service(timeout_sec=LIVENESS_S), f'service {name} not available'
        return client

    def call_async(self, srv_type: Any, name: str, request: Any) -> Any:
        return self.client(srv_type, name).call_async(request)

    @staticmethod
    def result(future: Any, timeout: float = LIVENESS_S) -> Any:
        done = threading.Event()
        future.add_done_callback(lambda _: done.set())
        assert done.wait(timeout), f'no answer within {timeout:.0f} s'
        return future.result()

    def call(self, srv_type: Any, name: str, request: Any, timeout: float = LIVENESS_S) -> Any:
        return self.result(self.call_async(srv_type, name, request), timeout)

    # parameters, through the node's parameter services

    def set_parameters(self, node: str, params: list[Any], atomically: bool = False) -> list[Any]:
        """Set rclpy ``Parameter`` objects on ``node`` (its full name); return the results."""
        from rcl_interfaces.srv import SetParameters, SetParametersAtomically

        msgs = [p.to_parameter_msg() for p in params]
        if atomically:
            return [self.call(SetParametersAtomically, f'{node}/set_parameters_atomically',
                              SetParametersAtomically.Request(parameters=msgs)).result]
        return self.call(SetParameters, f'{node}/set_parameters',
                         SetParameters.Request(parameters=msgs)).results

    def get_parameters(self, node: str, names: list[str], timeout: float = LIVENESS_S) -> list[Any]:
        """Python values of the named parameters of ``node``."""
        from rcl_interfaces.srv import GetParameters
        from rclpy.parameter import parameter_value_to_python

        answer = self.call(GetParameters, f'{node}/get_parameters',
                           GetParameters.Request(names=names), timeout)
        return [parameter_value_to_python(v) for v in answer.values]

    # topics

    def publisher(self, msg_type: Any, topic: str) -> Any:
        """A publisher on ``topic``, once the planner subscribes to it."""
        if topic not in self._publishers:
            self._publishers[topic] = self.node.create_publisher(msg_type, topic, 10)
        pub = self._publishers[topic]
        wait_until(lambda: pub.get_subscription_count() > 0, what=f'a subscriber on {topic}')
        return pub

    def inbox(self, msg_type: Any, topic: str) -> queue.Queue[Any]:
        """A queue of the messages arriving on ``topic``, once the planner publishes there."""
        if topic not in self._inboxes:
            box: queue.Queue[Any] = queue.Queue()
            sub = self.node.create_subscription(msg_type, topic, box.put, 10)
            self._inboxes[topic] = (sub, box)
        sub, box = self._inboxes[topic]
        wait_until(lambda: sub.get_publisher_count() > 0, what=f'a publisher on {topic}')
        return box


@pytest.fixture(scope='session')
def peer(ros_env: dict[str, str]) -> Iterator[Peer]:
    """The test process's ROS 2 node (its own context, in the session's DDS domain)."""
    p = Peer()
    yield p
    p.close()
