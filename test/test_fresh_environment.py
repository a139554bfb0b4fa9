# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The colcon-installed planner node runs with nothing installed but what package.xml declares.

A ROS user runs ``rosdep install``, ``colcon build`` and ``ros2 run trajplan_ros planner_node``.
The ``ros2`` command line is not on PyPI, so this test builds the next best thing: a fresh venv
(no pip, no system site-packages) holding only the ROS wheels of setup.py's ``ros`` extra and the
PyPI distributions that package.xml's python3-* run keys name (through test_dependencies.py's
table), with the distributions their ``Requires-Dist`` names, recursively. The files come from
this venv, hard-linked (or copied) to the same places, RECORD by RECORD. The installed node then
runs on that Python and a service call must reach the paper's goal: an import of anything that
package.xml does not declare would stop it.

A requirement's extras are not followed (yourdfpy's ``trimesh[easy]`` is plain trimesh here), so
the venv is smaller than what pip would install: a stricter test. Bench-only modules such as
scipy are absent, which the test checks to show that the venv really is restricted.
"""
from __future__ import annotations

from collections.abc import Iterable, Mapping
import importlib.metadata
import json
import os
from pathlib import Path
import shutil
import subprocess
import sys

from declared_dependencies import (is_python_key, KEY_DISTRIBUTIONS, NOT_ON_PYPI, package_keys,
                                   ROS_DISTRIBUTIONS, RUN_TAGS, setup_argument)
from nav_msgs.srv import GetPlan
from node_under_test import Install, LIVENESS_S, NodeProcess
import numpy as np
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
import pytest
from trajplan_ros.tools.bench.cases import PAPER_TARGET
from trajplan_ros.tools.ros_client import plan_request, RosClient

pytestmark = pytest.mark.system

PAPER_GOAL = tuple(PAPER_TARGET.tolist())
SITE = Path('lib', f'python{sys.version_info.major}.{sys.version_info.minor}', 'site-packages')

#: Variables through which this venv could reach the node: the ROS wheels' bootstrapper re-runs
#: Python once with LD_LIBRARY_PATH set for its own prefix, unless its guard is already set.
LEAKING = ('PYTHONPATH', 'PYTHONHOME', 'VIRTUAL_ENV', '_ROS_WHEELS_BOOTSTRAP_COMPLETE',
           'COVERAGE_PROCESS_START')

#: Run in the fresh venv: where the node's modules come from, and whether scipy is there.
PROBE = """
import importlib.util, json, sys
import numpy, rclpy, trajplan_ros, yourdfpy
print(json.dumps({'path': sys.path, 'scipy': importlib.util.find_spec('scipy') is not None,
                  'files': [m.__file__ for m in (numpy, rclpy, trajplan_ros, yourdfpy)]}))
"""


# --- the fresh venv -----------------------------------------------------------------------------

def declared_distributions() -> list[str]:
    """Return the ROS wheels (setup.py's ros extra) and the distributions of package.xml's keys."""
    python_keys = sorted(k for k in package_keys(*RUN_TAGS) if is_python_key(k))
    cmeel = [dist for dist, key in ROS_DISTRIBUTIONS.items() if key in package_keys(*RUN_TAGS)]
    return list(setup_argument('extras_require')['ros']) + cmeel + [KEY_DISTRIBUTIONS[k]
                                                                    for k in python_keys]


def requirement_closure(names: Iterable[str]) -> dict[str, importlib.metadata.Distribution]:
    """Return ``names`` and what their Requires-Dist name for this Python, recursively."""
    found: dict[str, importlib.metadata.Distribution] = {}
    pending = list(names)
    while pending:
        name = canonicalize_name(pending.pop())
        if name in found:
            continue
        found[name] = dist = importlib.metadata.distribution(name)
        for line in dist.requires or []:
            requirement = Requirement(line)
            if requirement.marker is None or requirement.marker.evaluate({'extra': ''}):
                pending.append(requirement.name)
    return found


def link_distribution(dist: importlib.metadata.Distribution, prefix: Path) -> int:
    """Hard-link (or copy) the files of ``dist``'s RECORD into venv ``prefix``; return how many."""
    assert dist.files is not None, f'{dist.metadata["Name"]}: no RECORD'
    count = 0
    for file in dist.files:
        source = Path(dist.locate_file(file))
        target = Path(os.path.normpath(prefix / SITE / file))
        assert target.is_relative_to(prefix), f'{file}: outside the venv'
        if not source.is_file() or target.exists():    # a .pyc never compiled; listed twice
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        try:
            os.link(source, target)
        except OSError:
            shutil.copy2(source, target)
        count += 1
    return count


@pytest.fixture(scope='module')
def fresh_venv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Return the prefix of a venv holding only the declared distributions and their closure."""
    prefix = tmp_path_factory.mktemp('fresh') / 'venv'
    subprocess.run([sys.executable, '-m', 'venv', '--without-pip', str(prefix)], check=True,
                   timeout=LIVENESS_S)
    for dist in requirement_closure(declared_distributions()).values():
        assert link_distribution(dist, prefix), f'{dist.metadata["Name"]}: no files'
    return prefix


def fresh_environment(base: Mapping[str, str], install: Install, prefix: Path) -> dict[str, str]:
    """Return ``base`` as ``source install/setup.bash`` over the fresh venv would make it."""
    def outside_this_venv(variable: str) -> str:
        paths = base.get(variable, '').split(os.pathsep)
        return os.pathsep.join(p for p in paths if p and not p.startswith(sys.prefix))

    env = {k: v for k, v in base.items() if k not in LEAKING}
    env['LD_LIBRARY_PATH'] = outside_this_venv('LD_LIBRARY_PATH')
    env['PATH'] = os.pathsep.join([str(prefix / 'bin'), outside_this_venv('PATH')])
    env = install.env(env)                                  # PYTHONPATH: the install only
    env['AMENT_PREFIX_PATH'] = os.pathsep.join([str(install.prefix), str(prefix)])
    env['PYTHONNOUSERSITE'] = '1'
    env['PYTHONDONTWRITEBYTECODE'] = '1'                    # the files are this venv's too
    return env


# --- the test -----------------------------------------------------------------------------------

def test_node_runs_with_only_the_declared_dependencies(
        fresh_venv: Path, colcon_install: Install, ros_env: dict[str, str],
        peer: RosClient) -> None:
    python = fresh_venv / 'bin' / 'python'
    env = fresh_environment(ros_env, colcon_install, fresh_venv)
    # the ROS wheels keep their ament index in the venv's prefix, cmeel's wheels (coal) in
    # their own prefix inside site-packages
    cmeel = next(fresh_venv.glob('lib/python3*/site-packages/cmeel.prefix'))
    # (a package with no wheel serves an option that is off by default: execution action)
    for package in (k for k in package_keys(*RUN_TAGS)
                    if not is_python_key(k) and k not in NOT_ON_PYPI):
        assert any((prefix / 'share/ament_index/resource_index/packages' / package).is_file()
                   for prefix in (fresh_venv, cmeel)), \
            f'{package}: no ROS or cmeel wheel of the install provides it'

    probe = subprocess.run([str(python), '-c', PROBE], cwd=fresh_venv, env=env, text=True,
                           capture_output=True, timeout=LIVENESS_S)   # cwd: not the checkout
    assert probe.returncode == 0, probe.stderr
    found = json.loads(probe.stdout)
    assert not found['scipy'], 'scipy (a bench extra) is importable: the venv is not fresh'
    assert not [p for p in found['path'] if p.startswith(sys.prefix)], found['path']
    roots = (str(fresh_venv), str(colcon_install.prefix))
    assert all(file.startswith(roots) for file in found['files']), found['files']

    node = NodeProcess([str(python), str(colcon_install.executable)], env)
    try:
        node.wait_for(r'trajplan\]: ready: ')
        mapped = Path(f'/proc/{node.pid}/maps').read_text(encoding='utf-8').split()
        assert not [f for f in mapped if f.startswith(sys.prefix)], f'libraries of {sys.prefix}'
        answer = peer.call(GetPlan, '/plan_trajectory', plan_request(PAPER_GOAL))
        assert answer.plan.poses, node.output
        last = answer.plan.poses[-1].pose.position
        assert np.linalg.norm(np.array([last.x, last.y, last.z]) - PAPER_GOAL) <= 1e-6
    finally:
        code = node.stop()
    assert code == 0, node.output
