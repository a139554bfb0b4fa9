# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
package.xml declares what the package needs at run time, with keys that rosdep knows.

* setup.py's ``install_requires`` (for pip) and package.xml's python3-* run keys (for rosdep)
  name the same distributions, through one table: ``DISTRIBUTION_KEYS``;
* every python3-* key is defined by rosdep itself (``rosdep_keys.yaml``, the entries copied
  from ros/rosdistro), so a misspelt key fails, and a pip key installs the table's distribution;
* every other key is a ROS package in the ament index (test keys: a wheel of the lint extra);
* every third-party module that a module of the package imports when it is loaded is declared
  (imports inside functions are optional extras: scipy for the bench, matplotlib for figures).

test_fresh_environment.py then runs the node with nothing but these declarations installed.
"""
from __future__ import annotations

import ast
from functools import lru_cache
import importlib.metadata
import os
from pathlib import Path
import sys
from typing import Any, Iterator, Mapping
import xml.etree.ElementTree as ET

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
PACKAGE = 'trajplan_ros'
ROSDEP_YAML = Path(__file__).with_name('rosdep_keys.yaml')

#: PyPI distribution (canonical name) -> its rosdep key. Adding a dependency: a line here, the
#: requirement in setup.py, the key in package.xml and its entry in rosdep_keys.yaml.
DISTRIBUTION_KEYS = {
    'defusedxml': 'python3-defusedxml',
    'numba': 'python3-numba',
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

#: package.xml's tags of what the package needs at run time (REP 140).
RUN_TAGS = ('depend', 'exec_depend')


# --- what setup.py and package.xml declare -----------------------------------------------------

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


# --- what rosdep and the ament index define ----------------------------------------------------

@lru_cache(maxsize=None)
def rosdep_definitions() -> dict[str, Any]:
    """Return the rosdep entries copied from ros/rosdistro: key -> rules per OS."""
    return yaml.safe_load(ROSDEP_YAML.read_text(encoding='utf-8'))


def pip_packages(rules: Any) -> Iterator[str]:
    """Yield every PyPI name of a rosdep entry's ``pip: packages:`` lists (for any OS)."""
    if isinstance(rules, dict):
        for installer, value in rules.items():
            if installer == 'pip' and isinstance(value, dict):
                yield from value.get('packages', [])
            else:
                yield from pip_packages(value)


def ament_prefixes() -> list[Path]:
    """Return the prefixes whose ament index holds the ROS packages: AMENT_PREFIX_PATH, venv."""
    paths = os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) + [sys.prefix]
    cmeel = Path(importlib.metadata.distribution('coal').locate_file('cmeel.prefix'))
    return [Path(p) for p in paths if p] + [cmeel]


def is_ros_package(name: str) -> bool:
    """Whether ``name`` is a ROS package registered in the ament index (as ``ros2 pkg`` sees)."""
    return any((prefix / 'share/ament_index/resource_index/packages' / name).is_file()
               for prefix in ament_prefixes())


# --- what the code imports ---------------------------------------------------------------------

def is_type_checking_block(node: ast.AST) -> bool:
    """Whether ``node`` is ``if TYPE_CHECKING:`` (imports for annotations only)."""
    if not isinstance(node, ast.If):
        return False
    test = node.test
    return getattr(test, 'id', None) == 'TYPE_CHECKING' or \
        getattr(test, 'attr', None) == 'TYPE_CHECKING'


def load_time_imports(tree: ast.Module) -> Iterator[str]:
    """Yield the top-level modules a module imports when it is loaded (not inside functions)."""
    pending: list[ast.AST] = list(tree.body)
    while pending:
        node = pending.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) or \
                is_type_checking_block(node):
            continue
        if isinstance(node, ast.Import):
            yield from (alias.name.partition('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level == 0 and node.module:
                yield node.module.partition('.')[0]
        else:
            pending.extend(ast.iter_child_nodes(node))


def all_imports(tree: ast.Module) -> Iterator[str]:
    """Yield the top-level modules a module imports anywhere, inside functions too."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            yield from (alias.name.partition('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.module.partition('.')[0]


def third_party_imports(load_time_only: bool = True) -> dict[str, set[str]]:
    """Return the package's third-party imports: top-level module -> the files importing it."""
    scan = load_time_imports if load_time_only else all_imports
    found: dict[str, set[str]] = {}
    for path in sorted((REPO / PACKAGE).rglob('*.py')):
        tree = ast.parse(path.read_text(encoding='utf-8'), filename=str(path))
        for module in scan(tree):
            if module != PACKAGE and module not in sys.stdlib_module_names:
                found.setdefault(module, set()).add(str(path.relative_to(REPO)))
    return found


@lru_cache(maxsize=None)
def module_distributions() -> Mapping[str, list[str]]:
    """Return the installed distributions of each top-level module, e.g. yaml: [PyYAML]."""
    return importlib.metadata.packages_distributions()


def key_of_module(module: str) -> str:
    """Return the key that declares ``module``: its ROS package, or its distribution's key."""
    if is_ros_package(module):
        return module
    dists = module_distributions().get(module)
    if not dists:
        return f'<no installed distribution provides {module!r}>'
    keys = {DISTRIBUTION_KEYS.get(canonicalize_name(d)) for d in dists} - {None}
    return min(keys) if keys else f'<distribution {dists} is not in DISTRIBUTION_KEYS>'


# --- the checks ---------------------------------------------------------------------------------

def test_install_requires_and_package_xml_name_the_same_distributions() -> None:
    mapped = {DISTRIBUTION_KEYS.get(d, f'<{d}: not in DISTRIBUTION_KEYS>')
              for d in install_requires() if d not in ROS_DISTRIBUTIONS}
    declared = {key for key in package_keys(*RUN_TAGS) if is_python_key(key)}
    assert {ROS_DISTRIBUTIONS[d] for d in install_requires() if d in ROS_DISTRIBUTIONS} <= \
        package_keys(*RUN_TAGS)
    assert mapped == declared, (f'in setup.py only: {sorted(mapped - declared)}; '
                                f'in package.xml only: {sorted(declared - mapped)}')


@pytest.mark.parametrize('key', sorted(k for k in package_keys() if is_python_key(k)))
def test_package_xml_python_key_is_a_rosdep_key(key: str) -> None:
    assert key in rosdep_definitions(), f'{key}: not a rosdep key (see {ROSDEP_YAML.name})'
    assert key in KEY_DISTRIBUTIONS, f'{key}: not in DISTRIBUTION_KEYS'


@pytest.mark.parametrize('dist, key', sorted(DISTRIBUTION_KEYS.items()))
def test_rosdep_key_installs_the_mapped_distribution(dist: str, key: str) -> None:
    assert key in rosdep_definitions(), f'{key}: not in {ROSDEP_YAML.name}'
    named = {canonicalize_name(p) for p in pip_packages(rosdep_definitions()[key])}
    assert named <= {dist}, f'{key}: rosdep pip-installs {sorted(named)}, not {dist}'
    if key.endswith('-pip'):
        assert named == {dist}, f'{key}: a pip key without pip packages'


def test_rosdep_copy_is_the_mapped_keys_with_their_source() -> None:
    assert set(rosdep_definitions()) == set(DISTRIBUTION_KEYS.values())
    header = ROSDEP_YAML.read_text(encoding='utf-8').partition('\n\n')[0]
    assert 'https://github.com/ros/rosdistro' in header and 'rosdep/python.yaml' in header
    assert any(len(w) == 40 and set(w) <= set('0123456789abcdef') for w in header.split())


@pytest.mark.parametrize('tag, key', sorted(
    {(tag, key) for tag, key in package_dependencies() if not is_python_key(key)}))
def test_ros_key_is_a_ros_package(tag: str, key: str) -> None:
    if tag == 'test_depend':
        wheel = 'ros-jazzy-' + key.replace('_', '-')
        assert wheel in setup_argument('extras_require')['lint'], \
            f'{key}: no {wheel} in the lint extra'
    else:
        assert is_ros_package(key), f'{key}: not in the ament index of {ament_prefixes()}'


def test_every_module_imported_at_load_time_is_declared() -> None:
    declared = package_keys(*RUN_TAGS)
    missing = [f'{module} ({key_of_module(module)}), imported by {", ".join(sorted(files))}'
               for module, files in sorted(third_party_imports().items())
               if key_of_module(module) not in declared]
    assert not missing, 'not declared in package.xml:\n' + '\n'.join(missing)


def test_every_declared_ros_package_is_imported() -> None:
    imported = {m for m in third_party_imports(load_time_only=False) if is_ros_package(m)}
    declared = {key for key in package_keys(*RUN_TAGS) if not is_python_key(key)}
    assert declared <= imported, f'declared, never imported: {sorted(declared - imported)}'
