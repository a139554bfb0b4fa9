# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
What setup.py and package.xml declare, read (not run), and the table that ties the two.

Shared by ``test_dependencies`` (each key resolves) and ``test_fresh_environment`` (the node
runs with nothing else installed).
"""
from __future__ import annotations

import ast
from pathlib import Path
from typing import Any
import xml.etree.ElementTree as ET

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

__all__ = ['DISTRIBUTION_KEYS', 'install_requires', 'is_python_key', 'KEY_DISTRIBUTIONS',
           'MODULE_PACKAGES', 'NOT_ON_PYPI', 'package_dependencies', 'package_keys', 'REPO',
           'ROS_DISTRIBUTIONS', 'RUN_TAGS', 'setup_argument']

REPO = Path(__file__).resolve().parents[1]

#: PyPI distribution (canonical name) -> its rosdep key. Adding a dependency: a line here, the
#: requirement in setup.py, the key in package.xml and its entry in rosdep_keys.yaml.
DISTRIBUTION_KEYS = {
    'defusedxml': 'python3-defusedxml',
    'numba': 'python3-numba-pip',
    'numpy': 'python3-numpy',
    'pytest': 'python3-pytest',
    'pyyaml': 'python3-yaml',
    'setuptools': 'python3-setuptools',
    'trimesh': 'python3-trimesh-pip',
    'yourdfpy': 'python3-yourdfpy-pip',
}
#: PyPI distributions that are ROS packages too (cmeel wheels with their ament index): their
#: rosdep key is the ROS package's name.
ROS_DISTRIBUTIONS = {'coal': 'coal'}
KEY_DISTRIBUTIONS = {key: dist for dist, key in DISTRIBUTION_KEYS.items()}
#: ROS packages with no wheel on PyPI: the pip route builds them from their sources (shared/),
#: so the venv's ament index lacks them; rosdep installs them from Jazzy's release.
NOT_ON_PYPI = ('control_msgs', 'moveit_msgs', 'tf2_ros_py')
#: The ROS packages whose Python module has another name: module -> package.
MODULE_PACKAGES = {'tf2_ros': 'tf2_ros_py'}

#: package.xml's tags of what the package needs at run time (REP 140).
RUN_TAGS = ('depend', 'exec_depend')


def setup_argument(name: str) -> Any:
    """Return the literal value of setup.py's ``setup(name=...)`` keyword (read, not run)."""
    tree = ast.parse((REPO / 'setup.py').read_text(encoding='utf-8'))
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and getattr(node.func, 'id', None) == 'setup':
            for keyword in node.keywords:
                if keyword.arg == name:
                    return ast.literal_eval(keyword.value)
    raise LookupError(f'setup.py: no setup({name}=...)')


def install_requires() -> set[str]:
    """Return the canonical names of the distributions in setup.py's install_requires."""
    return {canonicalize_name(Requirement(r).name) for r in setup_argument('install_requires')}


def package_dependencies() -> list[tuple[str, str]]:
    """Return package.xml's dependencies as (tag, key), e.g. ('exec_depend', 'rclpy')."""
    root = ET.parse(REPO / 'package.xml').getroot()
    return [(e.tag, (e.text or '').strip()) for e in root if e.tag.endswith('depend')]


def package_keys(*tags: str) -> set[str]:
    """Return the keys of package.xml's dependencies of the given tags (all without tags)."""
    return {key for tag, key in package_dependencies() if not tags or tag in tags}


def is_python_key(key: str) -> bool:
    """Whether a rosdep key names a Python distribution (rather than a ROS package)."""
    return key.startswith('python3-')
