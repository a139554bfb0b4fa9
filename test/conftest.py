# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Shared fixtures: the run's kernel cache, the colcon install, the node and a DDS peer.

Importing this file needs no ROS 2: rclpy and the interface packages are imported inside the
fixtures, so the core's tests run where ROS 2 is absent. The ROS tests themselves import rclpy
and fail loudly without it (nothing is skipped).

The node under test runs as its own process, the way ``ros2 run trajplan_ros planner_node``
runs it: the executable installed by ``colcon build`` (built once per session into a temporary
directory), with the environment ``source install/setup.bash`` would give it. The test process
and every node share one DDS domain chosen from the pid, with discovery kept on localhost.
"""
from __future__ import annotations

import functools
import os
import shlex
import shutil
import signal
import tempfile

# One cache of compiled kernels for the whole run, before anything imports numba: the source
# tree, the venv's copy and the colcon install then compile the kernels once, not each
# (tests of the cache itself set their own)
_KERNEL_CACHE = None
if 'NUMBA_CACHE_DIR' not in os.environ:
    _KERNEL_CACHE = os.environ['NUMBA_CACHE_DIR'] = tempfile.mkdtemp(prefix='trajplan-kernels-')

from pathlib import Path  # noqa: E402, I100 (after the cache folder is set)
import subprocess  # noqa: E402
import sys  # noqa: E402
from typing import Any, Callable, Iterator  # noqa: E402

from node_under_test import Install, NodeProcess, PACKAGE, REPO  # noqa: E402
import pytest  # noqa: E402


#: The test of a cold start, run first so that its compile fills the run's cache (test_kernels).
_FIRST = 'test_the_first_run_compiles_and_says_so_later_ones_load'


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Run the cold-start test first: the run then compiles the kernels once, not twice."""
    items.sort(key=lambda item: item.name != _FIRST)


@functools.lru_cache(maxsize=None)
def _every_kernel() -> None:
    from trajplan_ros.planning import prepare

    prepare()


@pytest.fixture(autouse=True)
def kernels_ready(request: pytest.FixtureRequest) -> None:
    """
    Compile or load every kernel, once, before each test but the cold start.

    A command compiles only what its plans need, and says so on stderr: a test that runs one
    (and reads its stderr, or a README block) sees what a user sees once the kernels are
    compiled, whatever tests ran before it. The cold-start test, run first, finds none.
    """
    if request.node.name != _FIRST:
        _every_kernel()


@pytest.fixture()
def empty_kernel_cache(tmp_path: Path) -> Path:
    """
    Return a kernel cache without kernels: the run's own while it has none, else a new one.

    A kernel's index is a ``.nbi`` file; other files there (the core stamp's memo) do not count.
    """
    if _KERNEL_CACHE is not None and not any(Path(_KERNEL_CACHE).rglob('*.nbi')):
        return Path(_KERNEL_CACHE)
    return tmp_path / 'cache'


def pytest_sessionfinish() -> None:
    """Remove the run's cache of compiled kernels; stop a build of control_msgs still going."""
    _InterfacesBuild.stop()
    if _KERNEL_CACHE is not None:
        shutil.rmtree(_KERNEL_CACHE, ignore_errors=True)


# --- environment and the colcon install ---------------------------------------------------------

@pytest.fixture(scope='session')
def ros_env() -> Iterator[dict[str, str]]:
    """Isolate this test run on DDS: a domain from the pid (1..100), localhost discovery."""
    patch = pytest.MonkeyPatch()
    patch.setenv('ROS_DOMAIN_ID', str(1 + os.getpid() % 100))
    patch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    yield dict(os.environ)
    patch.undo()


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


# --- ROS packages not on PyPI: control_msgs (execution), moveit_msgs (MoveIt), tf2 (frames) ------

#: The interface sources and their build script (neither package is on PyPI): the folder
#: ROS_INTERFACES_SRC names, else ``shared/ros_interfaces`` beside this clone.
ROS_INTERFACES = Path(os.environ.get('ROS_INTERFACES_SRC')
                      or REPO.parent / 'shared' / 'ros_interfaces')
#: tf2's Python side (tf2_ros_py and what it needs): TF2_SRC, else ``tf2`` beside the
#: interface sources (both are in ``shared/``).
TF2 = Path(os.environ.get('TF2_SRC') or ROS_INTERFACES.parent / 'tf2')
#: Each package a test needs, by the fixture that gives it: its sources, and how the node
#: loads it.
INTERFACES = {
    'control_msgs_env': ('control_msgs', ROS_INTERFACES,
                         'from trajplan_ros.ros.execution import action_type; action_type()'),
    'moveit_msgs_env': ('moveit_msgs', ROS_INTERFACES, 'from trajplan_ros.ros.moveit_interfaces '
                                                       'import moveit_types; moveit_types()'),
    'tf2_env': ('tf2_ros_py', TF2, 'import tf2_ros; tf2_ros.Buffer()'),
}
#: What the build needs besides the venv: without them the tests that need a build skip.
_COMPILERS = bool(shutil.which('cmake') and shutil.which('g++'))
#: Where they are built, once per venv (the script installs the rosidl generators into it).
INTERFACES_BUILD = Path(sys.prefix) / 'build' / 'ros_interfaces'


def _built(package: str) -> Path:
    """Return the file written when ``package``'s build succeeded (a stopped one leaves none)."""
    return INTERFACES_BUILD / f'built-{package}'


def _loads(fixture: str, env: dict[str, str]) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, '-c', INTERFACES[fixture][2]], env=env,
                          capture_output=True, text=True, timeout=120)


class _InterfacesBuild:
    """The build of the packages the run needs, started in the background at collection."""

    proc: subprocess.Popen | None = None
    log: Path | None = None
    packages: tuple[str, ...] = ()

    @classmethod
    def start(cls, fixtures: list[str]) -> None:
        """
        Start the build where it is needed and possible (the fixtures say why otherwise).

        One script run per source folder, in turn (they share the colcon workspace).
        """
        script = ROS_INTERFACES / 'build_ros_interfaces.sh'
        wanted = [INTERFACES[f] for f in fixtures
                  if not _built(INTERFACES[f][0]).is_file()
                  and _loads(f, dict(os.environ)).returncode != 0]
        runs = {source: [p for p, s, _ in wanted if s == source]
                for _, source, _ in wanted if (source / 'README.md').is_file()}
        cls.packages = tuple(p for packages in runs.values() for p in packages)
        if not cls.packages or not script.is_file() or not _COMPILERS:
            return
        INTERFACES_BUILD.mkdir(parents=True, exist_ok=True)
        cls.log = INTERFACES_BUILD / 'build.log'
        steps = ' && '.join(shlex.join(['bash', str(script), sys.prefix, str(source),
                                        str(INTERFACES_BUILD), *packages])
                            for source, packages in runs.items())
        with open(cls.log, 'w', encoding='utf-8') as log:
            cls.proc = subprocess.Popen(['bash', '-c', steps], stdout=log, stderr=log,
                                        stdin=subprocess.DEVNULL, start_new_session=True)

    @classmethod
    def wait(cls) -> None:
        """Wait for a started build; fail with the end of its log if it failed."""
        if cls.proc is None:
            return
        code = cls.proc.wait(timeout=1800)
        log = cls.log.read_text(encoding='utf-8', errors='replace')
        assert code == 0, f'build_ros_interfaces.sh failed:\n{log[-3000:]}'
        for package in cls.packages:
            _built(package).touch()
        cls.proc = None

    @classmethod
    def stop(cls) -> None:
        """Stop a build still running when the run ends (by its PID)."""
        if cls.proc is not None and cls.proc.poll() is None:
            os.killpg(cls.proc.pid, signal.SIGKILL)      # its session: colcon, cmake and g++
            cls.proc.wait()


def pytest_collection_finish(session: pytest.Session) -> None:
    """Start building the interfaces the run needs while the tests that do not run."""
    used = {name for item in session.items for name in getattr(item, 'fixturenames', ())}
    _InterfacesBuild.start([f for f in INTERFACES if f in used])


def _interfaces_env(fixture: str, ros_env: dict[str, str]) -> dict[str, str]:
    """
    Give an environment in which ``fixture``'s package loads; skip where it cannot be had.

    An importable package is used as it is. Else it is built from ``ROS_INTERFACES`` with its
    build_ros_interfaces.sh into ``INTERFACES_BUILD`` (once per venv, begun when the run is
    collected); a clone without those sources skips with that reason.
    """
    if _loads(fixture, ros_env).returncode == 0:
        return dict(ros_env)
    package, source, _ = INTERFACES[fixture]
    _InterfacesBuild.wait()
    install = INTERFACES_BUILD / 'install'
    if not _built(package).is_file():
        if not _COMPILERS:
            pytest.skip(f'{package} does not load, and this machine has no cmake and g++ to '
                        'build it')
        pytest.skip(f'{package} does not load, and {source} (its sources) or '
                    f'{ROS_INTERFACES}/build_ros_interfaces.sh is missing to build it (set '
                    'ROS_INTERFACES_SRC and TF2_SRC to the folders of the sources)')
    python = f'python{sys.version_info.major}.{sys.version_info.minor}'
    paths = {'PYTHONPATH': [str(p) for p in install.glob(f'*/lib/{python}/site-packages')],
             'LD_LIBRARY_PATH': [str(p) for p in install.glob('*/lib')]}
    env = dict(ros_env)
    for name, found in paths.items():
        env[name] = os.pathsep.join(filter(None, [*found, ros_env.get(name)]))
    loaded = _loads(fixture, env)
    assert loaded.returncode == 0, f'{package} built in {install} does not load: ' \
        f'{loaded.stderr[-2000:]}'
    return env


@pytest.fixture(scope='session')
def control_msgs_env(ros_env: dict[str, str]) -> dict[str, str]:
    """Give an environment in which control_msgs loads (about 1.5 min to build, once)."""
    return _interfaces_env('control_msgs_env', ros_env)


@pytest.fixture(scope='session')
def moveit_msgs_env(ros_env: dict[str, str]) -> dict[str, str]:
    """Give an environment in which moveit_msgs loads (about 5 min to build, once)."""
    return _interfaces_env('moveit_msgs_env', ros_env)


@pytest.fixture(scope='session')
def tf2_env(ros_env: dict[str, str]) -> dict[str, str]:
    """Give an environment in which tf2_ros loads (about 1 min to build, once)."""
    return _interfaces_env('tf2_env', ros_env)


# --- the node process ---------------------------------------------------------------------------

@pytest.fixture(scope='session')
def start_node(colcon_install: Install,
               ros_env: dict[str, str]) -> Iterator[Callable[..., NodeProcess]]:
    """
    Give a factory that runs the installed planner_node: ``start(*ros_args, ready=True)``.

    With ``ready`` it waits for the node's "ready" log line. ``env`` replaces the test
    process's environment, ``executable`` names another of the package's (demo_controller).
    Every node started is stopped (SIGINT, then SIGKILL) at the end of the session if a test
    has not stopped it.
    """
    started: list[NodeProcess] = []

    def start(*ros_args: str, ready: bool = True, env: dict[str, str] | None = None,
              executable: str = 'planner_node') -> NodeProcess:
        argv = [str(colcon_install.executable.with_name(executable))] + (
            ['--ros-args', *ros_args] if ros_args else [])
        node = NodeProcess(argv, colcon_install.env(env or os.environ))
        started.append(node)
        if ready:
            node.wait_for(r'trajplan\]: ready: ')
        return node

    yield start
    for node in started:
        node.stop()


# --- the test process's side of DDS -------------------------------------------------------------

@pytest.fixture(scope='session')
def peer(ros_env: dict[str, str]) -> Iterator[Any]:
    """Give the test process a ROS 2 node (``tools.ros_client.RosClient``) in the domain."""
    from trajplan_ros.tools.ros_client import RosClient

    client = RosClient('trajplan_test_peer')
    yield client
    client.close()
