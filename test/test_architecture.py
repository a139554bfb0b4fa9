# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The package's architecture, checked on its source: layers, imports, function size, headers.

The folders are layers: ``kinematics`` < ``motion`` < ``collision`` < ``search`` < ``planning``
< ``ros`` and ``tools``. A module may import from its own layer and the layers below it, never
above, and the import graph between our modules has no cycles. Nothing below ``ros`` may import
ROS.
"""
import ast
import importlib
from pathlib import Path
import re

import pytest


PACKAGE = Path(__file__).resolve().parents[1] / 'trajplan_ros'
#: What each layer may import from this package (besides itself).
ALLOWED = {
    'kinematics': set(),
    'motion': {'kinematics'},
    'collision': {'kinematics', 'motion'},
    'search': {'kinematics', 'motion', 'collision'},
    'planning': {'kinematics', 'motion', 'collision', 'search'},
    'ros': {'kinematics', 'motion', 'collision', 'search', 'planning'},
    'tools': {'kinematics', 'motion', 'collision', 'search', 'planning', 'ros'},
}
#: Top-level names of ROS 2 Python packages: none may appear in the numpy core.
ROS_PACKAGES = {'rclpy', 'rcl_interfaces', 'geometry_msgs', 'nav_msgs', 'sensor_msgs',
                'std_msgs', 'trajectory_msgs', 'builtin_interfaces', 'ament_index_python'}
#: The layers below ``ros``: the library, importable without ROS.
CORE = {'kinematics', 'motion', 'collision', 'search', 'planning'}
MAX_FUNCTION_LINES = 60


def modules() -> dict[str, ast.Module]:
    """Parse every module of the package, keyed by dotted name."""
    out = {}
    for path in sorted(PACKAGE.rglob('*.py')):
        parts = path.relative_to(PACKAGE.parent).with_suffix('').parts
        name = '.'.join(parts[:-1] if parts[-1] == '__init__' else parts)
        out[name] = ast.parse(path.read_text(encoding='utf-8'), filename=str(path))
    return out


def imported(name: str, tree: ast.Module) -> set[str]:
    """Return the absolute names of every module ``tree`` imports, anywhere in it."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, f'{name}: relative import; use absolute imports'
            found.add(node.module)
            found.update(f'{node.module}.{alias.name}' for alias in node.names)
    return found


def layer(module: str) -> str | None:
    parts = module.split('.')
    return parts[1] if len(parts) > 1 and parts[1] in ALLOWED else None


MODULES = modules()


def ours(name: str, tree: ast.Module) -> set[str]:
    """Return the modules of this package that ``name`` imports."""
    return {m for m in imported(name, tree) if m in MODULES and m != name}


def test_every_module_is_in_a_layer() -> None:
    assert {layer(m) for m in MODULES} - {None} == set(ALLOWED)
    assert [m for m in MODULES if layer(m) is None] == ['trajplan_ros']


@pytest.mark.parametrize('name', sorted(MODULES))
def test_imports_go_down_the_layers_only(name: str) -> None:
    if layer(name) is None:                    # the package root re-exports the library API
        assert {layer(m) for m in ours(name, MODULES[name])} <= CORE
        return
    for target in ours(name, MODULES[name]):
        assert layer(target) in ALLOWED[layer(name)] | {layer(name)}, f'{name} -> {target}'


@pytest.mark.parametrize('name', [m for m in sorted(MODULES)
                                  if layer(m) in CORE])
def test_the_core_imports_no_ros(name: str) -> None:
    roots = {m.split('.')[0] for m in imported(name, MODULES[name])}
    assert not roots & ROS_PACKAGES, f'{name} imports {roots & ROS_PACKAGES}'


def test_no_import_cycles_between_our_modules() -> None:
    # a package's __init__ importing its own modules is not a cycle; a module importing names
    # from its package (which imports it) is one, and shows up here as two edges
    graph = {name: ours(name, tree) for name, tree in MODULES.items()}
    state: dict[str, int] = {}

    def visit(node: str, path: list[str]) -> None:
        state[node] = 1
        for nxt in graph[node]:
            if state.get(nxt) == 1:
                pytest.fail('import cycle: ' + ' -> '.join(path[path.index(nxt):] + [nxt]))
            if nxt not in state:
                visit(nxt, path + [nxt])
        state[node] = 2

    for name in graph:
        if name not in state:
            visit(name, [name])


@pytest.mark.parametrize('name', sorted(MODULES))
def test_no_importlib_imports_of_our_own_modules(name: str) -> None:
    for node in ast.walk(MODULES[name]):
        if isinstance(node, ast.Call) and getattr(node.func, 'attr', '') == 'import_module':
            text = ast.unparse(node.args[0])
            assert not re.search(r'\b(trajplan_ros|__package__|__name__)\b', text), \
                f'{name}: importlib.import_module({text}): import our modules directly'


@pytest.mark.parametrize('name', sorted(MODULES))
def test_functions_are_short(name: str) -> None:
    long = [f'{node.name} ({node.end_lineno - node.lineno + 1} lines)'
            for node in ast.walk(MODULES[name])
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
            and node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES]
    assert not long, f'{name}: ' + ', '.join(long)


TESTS = Path(__file__).resolve().parent


@pytest.mark.parametrize('path', sorted(TESTS.glob('*.py')), ids=lambda p: p.name)
def test_no_test_module_imports_another(path: Path) -> None:
    # what tests share lives in helper modules (node_under_test, profile_cases, ...) or in
    # conftest's fixtures, so that any one test module runs alone
    tree = ast.parse(path.read_text(encoding='utf-8'))
    for node in ast.walk(tree):
        names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                 else [node.module or ''] if isinstance(node, ast.ImportFrom) else [])
        for name in names:
            assert not (name.startswith('test_') or name == 'conftest'), \
                f'{path.name} imports {name}'


@pytest.mark.parametrize('name', sorted(modules()))
def test_every_module_imports(name: str) -> None:
    # a command nothing else imports (the node benchmarks) must not rot unseen
    importlib.import_module(name)
