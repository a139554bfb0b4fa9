# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
package.xml declares what the package needs at run time, with keys that rosdep knows.

* setup.py's ``install_requires`` (for pip) and package.xml's python3-* run keys (for rosdep)
  name the same distributions, through one table: ``DISTRIBUTION_KEYS``;
* every python3-* key is defined by rosdep itself (``rosdep_keys.yaml``, the entries copied
  from ros/rosdistro) or by the package's own rosdep source (``resource/rosdep.yaml``), so a
  misspelt key fails, and a pip key installs the table's distribution;
* every key resolves on Ubuntu 24.04 (noble), Jazzy's platform, as ``rosdep install`` resolves
  it there: to pip, to an apt package noble has (``ubuntu_noble_apt.txt``) or to a ROS package
  that Jazzy releases (``rosdistro_jazzy.yaml``);
* the tests run at the oldest numba that setup.py admits, the one the rosdep source asks for;
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

from declared_dependencies import (DISTRIBUTION_KEYS, install_requires, is_python_key,
                                   KEY_DISTRIBUTIONS, MODULE_PACKAGES, NOT_ON_PYPI,
                                   package_dependencies,
                                   package_keys, REPO, ROS_DISTRIBUTIONS, RUN_TAGS,
                                   setup_argument)
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
from packaging.version import Version
import pytest
import yaml

PACKAGE = 'trajplan_ros'
ROSDEP_YAML = Path(__file__).with_name('rosdep_keys.yaml')
#: The package's own rosdep source, for keys rosdistro lacks (a user lists it before rosdep's).
SHIPPED_ROSDEP_YAML = REPO / 'resource' / 'rosdep.yaml'
#: Jazzy's release platforms and the repositories of the ROS packages package.xml names.
ROSDISTRO_YAML = Path(__file__).with_name('rosdistro_jazzy.yaml')
#: The apt packages of Ubuntu noble that rosdep may resolve a key to, outside ROS's repository.
NOBLE_APT = Path(__file__).with_name('ubuntu_noble_apt.txt')
#: The installers rosdep names in a rule (REP 111), as opposed to an OS release's codename.
INSTALLERS = ('apt', 'pip', 'source')


# --- what rosdep and the ament index define ----------------------------------------------------

@lru_cache(maxsize=None)
def copied_definitions() -> dict[str, Any]:
    """Return the rosdep entries copied from ros/rosdistro: key -> rules per OS."""
    return yaml.safe_load(ROSDEP_YAML.read_text(encoding='utf-8'))


@lru_cache(maxsize=None)
def shipped_definitions() -> dict[str, Any]:
    """Return the entries of the package's own rosdep source."""
    return yaml.safe_load(SHIPPED_ROSDEP_YAML.read_text(encoding='utf-8'))


def rosdep_definitions() -> dict[str, Any]:
    """Return every key rosdep knows here; the shipped source is listed first, so it wins."""
    return {**copied_definitions(), **shipped_definitions()}


def pip_requirements(rules: Any) -> Iterator[Requirement]:
    """Yield every requirement of a rosdep entry's ``pip: packages:`` lists (for any OS)."""
    if isinstance(rules, dict):
        for installer, value in rules.items():
            if installer == 'pip' and isinstance(value, dict):
                yield from (Requirement(p) for p in value.get('packages', []))
            else:
                yield from pip_requirements(value)


def pip_packages(rules: Any) -> Iterator[str]:
    """Yield every PyPI name of a rosdep entry's ``pip: packages:`` lists (for any OS)."""
    yield from (requirement.name for requirement in pip_requirements(rules))


# --- how rosdep resolves a key on Ubuntu noble --------------------------------------------------

@lru_cache(maxsize=None)
def jazzy_packages(os_name: str, codename: str) -> frozenset[str]:
    """Return the ROS packages Jazzy releases, empty unless it releases for that platform."""
    distribution = yaml.safe_load(ROSDISTRO_YAML.read_text(encoding='utf-8'))
    if codename not in distribution['release_platforms'].get(os_name, []):
        return frozenset()
    return frozenset(package for name, repository in distribution['repositories'].items()
                     for package in repository['release'].get('packages', [name]))


@lru_cache(maxsize=None)
def noble_apt_packages() -> frozenset[str]:
    """Return the apt packages of ``ubuntu_noble_apt.txt``."""
    lines = NOBLE_APT.read_text(encoding='utf-8').splitlines()
    return frozenset(line.strip() for line in lines if line.strip() and not line.startswith('#'))


def rule_for(rules: Any, os_name: str, codename: str) -> Any:
    """Return an entry's rule for one OS release (REP 111: OS, then codename, ``*`` for any)."""
    rule = rules.get(os_name, rules.get('*')) if isinstance(rules, dict) else None
    if isinstance(rule, dict) and not set(rule) & set(INSTALLERS):
        rule = rule.get(codename, rule.get('*'))
    return rule


def resolve(key: str, definitions: Mapping[str, Any], os_name: str = 'ubuntu',
            codename: str = 'noble') -> tuple[str, list[str]] | None:
    """
    Return what ``rosdep install`` installs for ``key`` there: (installer, packages).

    None where nothing does: an unknown key, a rule that names no package, or apt packages that
    the release does not have.
    """
    if key in definitions:
        rule = rule_for(definitions[key], os_name, codename)
        if isinstance(rule, list):
            rule = {'apt': {'packages': rule}}
        if not isinstance(rule, dict) or len(rule) != 1:
            return None
        (installer, spec), = rule.items()
        packages = spec.get('packages', []) if isinstance(spec, dict) else spec
        if installer not in INSTALLERS or not packages:
            return None
        if installer == 'apt' and not set(packages) <= noble_apt_packages():
            return None
        return installer, list(packages)
    if key in jazzy_packages(os_name, codename):
        return 'apt', ['ros-jazzy-' + key.replace('_', '-')]
    return None


def ament_prefixes() -> list[Path]:
    """Return the prefixes whose ament index holds the ROS packages: AMENT_PREFIX_PATH, venv."""
    paths = os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) + [sys.prefix]
    cmeel = Path(importlib.metadata.distribution('coal').locate_file('cmeel.prefix'))
    return [Path(p) for p in paths if p] + [cmeel]


def is_ros_package(name: str) -> bool:
    """
    Whether ``name`` is a ROS package registered in the ament index (as ``ros2 pkg`` sees).

    A package with no wheel (``NOT_ON_PYPI``) is one if Jazzy releases it.
    """
    if name in NOT_ON_PYPI:
        return name in jazzy_packages('ubuntu', 'noble')
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
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
              and node.func.id == 'lazy' and node.args
              and isinstance(node.args[0], ast.Constant)):       # kinematics.lazy_modules
            yield node.args[0].value.partition('.')[0]


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
    upstream = set(DISTRIBUTION_KEYS.values()) - set(shipped_definitions())
    assert set(copied_definitions()) == upstream | {'python3-numba'}
    header = ROSDEP_YAML.read_text(encoding='utf-8').partition('\n\n')[0]
    assert 'https://github.com/ros/rosdistro' in header and 'rosdep/python.yaml' in header
    assert any(len(w) == 40 and set(w) <= set('0123456789abcdef') for w in header.split())


@pytest.mark.parametrize('key', sorted(package_keys()))
def test_key_resolves_on_ubuntu_noble(key: str) -> None:
    assert resolve(key, rosdep_definitions()) is not None, \
        f'{key}: rosdep installs nothing for it on Ubuntu 24.04 (noble)'


def test_a_key_noble_has_no_package_for_resolves_to_nothing() -> None:
    assert resolve('python3-numba', rosdep_definitions()) is None      # noble has no numba
    assert resolve('python3-numba', rosdep_definitions(), 'debian', 'bookworm') is None
    assert resolve('no_such_package', rosdep_definitions()) is None
    assert resolve('rclpy', rosdep_definitions()) == ('apt', ['ros-jazzy-rclpy'])
    assert resolve('rclpy', rosdep_definitions(), 'ubuntu', 'jammy') is None


def test_shipped_numba_key_asks_for_setup_pys_floor_and_the_tests_run_there() -> None:
    requirements = [Requirement(r) for r in setup_argument('install_requires')]
    floor = next(r.specifier for r in requirements if r.name == 'numba')
    shipped, = pip_requirements(shipped_definitions()[DISTRIBUTION_KEYS['numba']])
    assert shipped.specifier == floor, f'resource/rosdep.yaml asks for {shipped}, setup.py {floor}'
    oldest, = (s.version for s in floor if s.operator == '>=')
    assert Version(importlib.metadata.version('numba')) == Version(oldest), \
        f'the tests run on numba {importlib.metadata.version("numba")}, not the floor {oldest}'


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
    imported = {MODULE_PACKAGES.get(m, m) for m in third_party_imports(load_time_only=False)
                if is_ros_package(MODULE_PACKAGES.get(m, m))}
    declared = {key for key in package_keys(*RUN_TAGS) if not is_python_key(key)}
    assert declared <= imported, f'declared, never imported: {sorted(declared - imported)}'
