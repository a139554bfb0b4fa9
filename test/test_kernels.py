# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The compiled kernels' policy: no GIL, a disk cache that can never run stale, and a fallback.

What each kernel computes is tested with its concept (test_arm.py: the chain walk against
homogeneous transforms and its Jacobian against finite differences; test_urdf_import.py and
test_chain_bench.py: URDF arms against yourdfpy's FK).
"""
from __future__ import annotations

import ast
from functools import cache
import inspect
import os
from pathlib import Path
import re
import subprocess
import sys
import threading

import numpy as np
import pytest
from trajplan_ros import ArmModel, plan
from trajplan_ros.kinematics import forward
from trajplan_ros.kinematics import parallel_compile
from trajplan_ros.kinematics.jit import CORE, core_stamp, FIRST_COMPILE, kernels
from trajplan_ros.planning import prepare, RewardPunishment
from trajplan_ros.tools.bench.cases import PAPER_TARGET
from trajplan_ros.tools.bench.cases import PUBLISHED

PACKAGE = Path(__file__).resolve().parents[1] / 'trajplan_ros'
#: The modules whose sources key the kernels' cache (``jit.CORE``).
CORE_MODULES = tuple(f'trajplan_ros.{folder.name}' for folder in CORE)


@cache
def kernel_modules() -> dict[Path, ast.Module]:
    """Return every module of the package that defines a ``@kernel``, parsed (once)."""
    found = {}
    for path in sorted(PACKAGE.rglob('*.py')):
        tree = ast.parse(path.read_text(encoding='utf-8'))
        if any(isinstance(d, ast.Name) and d.id == 'kernel'
               for node in ast.walk(tree) if isinstance(node, ast.FunctionDef)
               for d in node.decorator_list):
            found[path] = tree
    return found


def test_every_kernel_module_is_found() -> None:
    assert Path(forward.__file__).resolve() in kernel_modules()
    assert len(kernels()) >= 1


@pytest.mark.parametrize('path', sorted(kernel_modules()), ids=lambda p: p.name)
def test_kernels_read_only_names_of_the_core(path: Path) -> None:
    # the cache is keyed by the core's sources (jit.core_stamp): a kernel that read a constant
    # or called a function from elsewhere could run with an old copy of it compiled in
    assert any(folder in path.parents for folder in CORE), path
    tree = kernel_modules()[path]
    imported = {alias.asname or alias.name: node.module for node in tree.body
                if isinstance(node, ast.ImportFrom) for alias in node.names}
    for node in tree.body:
        if not isinstance(node, ast.FunctionDef) or not any(
                isinstance(d, ast.Name) and d.id == 'kernel' for d in node.decorator_list):
            continue
        read = {n.id for stmt in node.body for n in ast.walk(stmt)
                if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}
        foreign = {name: imported[name] for name in read & imported.keys()
                   if not imported[name].startswith(CORE_MODULES)}
        assert not foreign, f'{path.name}: kernel {node.name} reads {foreign}'


def test_kernels_call_only_kernels_of_the_core() -> None:
    # at run time too: a kernel made otherwise than with @kernel would escape the AST check
    for k in kernels():
        assert Path(k.py_func.__code__.co_filename).resolve() in kernel_modules(), k
        for name, value in inspect.getclosurevars(k.py_func).globals.items():
            if hasattr(value, 'py_func'):                          # a kernel that it calls
                assert value in kernels(), (k, name)
            elif isinstance(value, type) and issubclass(value, tuple):    # a record it builds
                assert hasattr(value, '_fields') and value.__module__.startswith(
                    'trajplan_ros.'), (k, name)
            elif not isinstance(value, (int, float, tuple, np.ndarray)):
                assert value is np, (k, name)


def test_a_change_anywhere_in_the_core_changes_every_kernels_cache_key(tmp_path) -> None:
    core = tuple(tmp_path / folder.name for folder in CORE)
    for folder in core:
        (folder / 'sub').mkdir(parents=True)
        (folder / 'a.py').write_text('X = 1\n')
    before = core_stamp(core)
    assert core_stamp(core) == before
    (core[1] / 'sub' / 'b.py').write_text('def f():\n    return 2\n')
    core_stamp.cache_clear()
    assert core_stamp(core) != before
    (core[1] / 'sub' / 'b.py').unlink()
    core_stamp.cache_clear()
    assert core_stamp(core) == before
    (core[0] / 'a.py').write_text('X = 2\n')
    core_stamp.cache_clear()
    assert core_stamp(core) != before
    core_stamp.cache_clear()


def test_comments_and_docstrings_keep_the_cache_key_code_changes_it(tmp_path) -> None:
    core = (tmp_path / 'core',)
    core[0].mkdir()
    source = core[0] / 'a.py'
    source.write_text('"""A module."""\nX = 1\n\n\ndef f():\n    """F."""\n    return X\n')
    before = core_stamp(core)
    source.write_text('"""Its docstring, rewritten."""\n# a comment\nX = 1  # one\n\n\n'
                      'def f():\n    """Another."""\n\n    return X\n')
    core_stamp.cache_clear()
    assert core_stamp(core) == before
    for code in ('X = 2\n\n\ndef f():\n    return X\n',        # a constant
                 'X = 1\n\n\ndef f():\n    return "F."\n'):      # a string that is no docstring
        source.write_text(code)
        core_stamp.cache_clear()
        assert core_stamp(core) != before
    core_stamp.cache_clear()


def test_numba_still_has_the_caching_names_jit_relies_on() -> None:
    # jit.py subclasses numba's cache locators and sets a dispatcher's cache (private API):
    # a numba release that moves them must fail here, by name, not deep inside a plan
    from numba.core import caching
    for name in ('UserProvidedCacheLocator', 'InTreeCacheLocator', 'UserWideCacheLocator',
                 'CompileResultCacheImpl', 'FunctionCache'):
        assert hasattr(caching, name), f'numba.core.caching.{name} is gone'
    assert hasattr(caching.CompileResultCacheImpl, '_locator_classes')
    assert hasattr(caching.FunctionCache, '_impl_class')
    for locator in (caching.UserProvidedCacheLocator, caching.InTreeCacheLocator):
        for method in ('get_source_stamp', 'get_disambiguator', 'get_suitable_cache_subpath'):
            assert hasattr(locator, method), f'{locator.__name__}.{method} is gone'
    prepare()
    for k in kernels():
        assert isinstance(k._cache, caching.FunctionCache), k
        index = k._cache._cache_file._index_path
        assert Path(index).name.startswith(f'{k.py_func.__module__.rsplit(".", 1)[-1]}.'
                                           f'{k.py_func.__qualname__}-kernel.'), index


def test_kernels_are_cached_under_the_core_stamp() -> None:
    prepare()
    for k in kernels():
        assert k._cache._impl.locator.get_source_stamp() == core_stamp(), k


def test_every_kernel_releases_the_gil_and_caches() -> None:
    prepare()
    for k in kernels():
        assert k.targetoptions.get('nogil') is True, k
        assert k.targetoptions.get('fastmath') in (None, False), k
        assert k.stats.cache_path, k


def test_prepare_compiles_what_every_arm_needs() -> None:
    # a kernel compiled during a plan would cost that plan seconds (and the node's plans end
    # at max_planning_time): URDF arms and other modes must find every kernel ready
    prepare()
    before = {k: len(k.overloads) for k in kernels()}
    for name in ('so101', 'panda'):
        published = PUBLISHED[name]
        arm = ArmModel.from_urdf(published.urdf, published.base_link, published.tip_link)
        goal = arm.tool(np.zeros((1, arm.n_joints)))[0][0] * 0.9
        for mode in ('free', 'radial'):
            plan(goal, arm=arm, mode=mode, seed=0, max_planning_time=0.5)
    # nor other kinds of input: a read-only goal, settings given as integers
    plan(PAPER_TARGET, seed=0, shaping=RewardPunishment(k=10000, j=3))
    assert {k: len(k.overloads) for k in kernels()} == before


def test_a_first_plans_kernels_are_in_the_recorded_order() -> None:
    # the helper process compiles from this list: a kernel whose types changed since it was
    # recorded would be left to the first plan alone (record it anew: parallel_compile.record)
    script = ('from trajplan_ros.kinematics.jit import kernels\n'
              'from trajplan_ros.planning.planner import _WARM_UP_GOAL, prepare\n'
              'from trajplan_ros.planning.request import PlanRequest\n'
              'prepare(PlanRequest(_WARM_UP_GOAL))\n'
              'for k in kernels():\n'
              '    for args in k.overloads:\n'
              '        print(k.py_func.__module__, k.py_func.__qualname__, args, sep="|")\n')
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=300, cwd=Path(__file__).resolve().parents[1])
    assert done.returncode == 0, done.stderr
    loaded = {tuple(line.split('|')) for line in done.stdout.splitlines()}
    assert len(loaded) >= 10
    for run in parallel_compile.RUNS:
        listed = {(module, name, str(args))
                  for module, name, args in parallel_compile.recorded(run)}
        assert loaded <= listed, loaded - listed


def test_a_kernel_another_process_compiles_is_skipped_or_waited_for(monkeypatch) -> None:
    prepare()
    kernel = forward.walk_chain
    args = next(iter(kernel.overloads))
    monkeypatch.setattr(parallel_compile, '_active', [True])
    path = parallel_compile._lock_path(kernel, args)
    path.parent.mkdir(parents=True, exist_ok=True)
    holder = subprocess.Popen(
        [sys.executable, '-c', 'import fcntl, sys\n'
         f'lock = open({str(path)!r}, "a")\n'
         'fcntl.flock(lock, fcntl.LOCK_EX)\n'
         'print("held", flush=True)\n'
         'sys.stdin.readline()\n'], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline() == 'held\n'
        with parallel_compile.claim(kernel, args, wait=False) as mine:
            assert not mine                                    # the helper goes on
        waited: list[bool] = []

        def wait_for_it() -> None:
            with parallel_compile.claim(kernel, args) as mine:
                waited.append(mine)

        waiter = threading.Thread(target=wait_for_it)
        waiter.start()
        waiter.join(0.5)
        assert waiter.is_alive() and not waited                # a plan waits for it
        holder.stdin.write('\n')
        holder.stdin.flush()
        waiter.join(30)
        assert waited == [True]
    finally:
        holder.kill()
        holder.wait(30)
    with parallel_compile.claim(kernel, args) as mine:         # and a callee's claim inside
        with parallel_compile.claim(kernel, args) as again:    # its caller's does not block
            assert mine and again


def run_plan(env: dict[str, str]) -> subprocess.CompletedProcess:
    """Run ``trajplan plan`` on the paper's target in a new process with ``env``."""
    return subprocess.run([sys.executable, '-m', 'trajplan_ros.tools.cli', 'plan', '0.151171',
                           '0.19162', '0.172124'], capture_output=True, text=True, timeout=300,
                          env=env, cwd=Path(__file__).resolve().parents[1])


@pytest.mark.system
def test_the_first_run_compiles_and_says_so_later_ones_load(empty_kernel_cache: Path) -> None:
    env = {**os.environ, 'NUMBA_CACHE_DIR': str(empty_kernel_cache)}
    first = run_plan(env)
    assert first.returncode == 0, first.stderr
    said = first.stderr.splitlines()
    assert said[0].startswith('trajplan: compiling ') and 'for the first time' in said[0], said
    assert FIRST_COMPILE in said[0]
    assert said[1].startswith('trajplan: compiled ') and 'planning kernels in' in said[1], said
    assert 'on two cores' in said[1], said                    # with the helper process
    again = run_plan(env)
    assert again.returncode == 0, again.stderr
    assert again.stderr == ''

    def plan_only(out: str) -> str:
        return re.sub(r'planned in \S+ ms', '', out)

    assert plan_only(again.stdout) == plan_only(first.stdout)


def test_without_a_writable_cache_it_compiles_and_warns_once() -> None:
    # numba's only locator is then the user's folder, and that cannot be made: as with a
    # read-only package folder and a read-only HOME (a container run as another user). Every
    # kernel is then compiled uncached; one is enough to show it (the whole core takes a
    # cold start's half minute)
    env = {**os.environ, 'NUMBA_CACHE_LOCATOR_CLASSES':
           'trajplan_ros.kinematics.jit.UserProvidedLocator',
           'NUMBA_CACHE_DIR': '/dev/null/cache'}
    script = ('import numpy as np, trajplan_ros\n'
              'from trajplan_ros.kinematics.jit import kernels\n'
              'from trajplan_ros.motion.time_law import motion_times, servo_law\n'
              'law = servo_law(np.array([0.5, 0.25]))\n'
              'print(motion_times(law, np.array([[1.0, 1.0]]), np.zeros(2))[0])\n'
              'print(sum(bool(k.stats.cache_path) for k in kernels()), len(kernels()))\n')
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=300, env=env, cwd=Path(__file__).resolve().parents[1])
    assert done.returncode == 0, done.stderr
    time, cached = done.stdout.split('\n')[:2]
    assert float(time) == 4.0
    assert int(cached.split()[0]) == 0 and int(cached.split()[1]) > 20     # none cached
    assert done.stderr.count('set NUMBA_CACHE_DIR to a writable folder') == 1, done.stderr
