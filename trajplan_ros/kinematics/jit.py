# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
How the planning core compiles its kernels: numba's ``njit``, with one cache policy.

Every kernel is ``@kernel``: compiled by numba with ``nogil=True`` (the node's executor thread
runs while a plan computes) and cached on disk, so that a process after the first loads the
machine code instead of compiling it. The cache is kept where ``NUMBA_CACHE_DIR`` says, else
beside the source (the package's ``__pycache__``), else in the user's cache folder
(``~/.cache/numba``); where none is writable the kernels are compiled in every process, with one
warning saying how to set ``NUMBA_CACHE_DIR``.

numba's own cache is keyed by the kernel's file alone: it would keep a kernel whose callee in
another file changed, with the callee's old code and constants compiled in. Ours is keyed by
the package version and a hash of the code of every source file of the core (the folders of
``CORE``, ``core_stamp``): any change of code there recompiles every kernel, so a kernel may
call kernels and read constants of other core files and can never run stale. The hash is of
each file's syntax tree without docstrings, and a kernel's cache file is named without its
line number, so an edit of comments or docstrings alone keeps every kernel.

This reaches into numba's caching classes (``numba.core.caching``); ``setup.py`` pins the range
of numba releases tested, and ``test_kernels`` checks the names used here.

``warm_up`` compiles or loads the kernels a run calls, so that no plan pays for it; it says when
it begins to compile, and reports how long it took and whether anything had to be compiled.
When it compiles, a helper process compiles the same kernels from the other end, on the other
core (``parallel_compile``).
"""
from __future__ import annotations

import ast
from dataclasses import dataclass
import functools
import hashlib
from importlib import metadata
import logging
import os
from pathlib import Path
import time
from typing import Any, Callable

import numba
from numba.core import caching, event, sigutils, types

import trajplan_ros.kinematics.parallel_compile as parallel_compile

__all__ = ['CORE', 'Warmup', 'core_stamp', 'inlined_kernel', 'kernel', 'kernels', 'warm_up']

_LOG = logging.getLogger('trajplan_ros')
#: The folders whose sources key every kernel's cache: the kernels and all they read.
CORE = tuple(Path(__file__).resolve().parents[1] / name
             for name in ('kinematics', 'motion', 'collision', 'search', 'planning'))
#: How long compiling takes (doc/benchmarks.md: the first start).
FIRST_COMPILE = ('about 25 s for the paper arm without a scene, 35 s for every kernel, on two '
                 'idle cores (a helper process compiles beside); longer on a busy machine')
#: Every kernel made by ``kernel``, with the call that compiles it (see ``warm_up``).
_KERNELS: list[Any] = []
_warned: list[bool] = []


def _version() -> str:
    try:
        return metadata.version('trajplan_ros')
    except metadata.PackageNotFoundError:       # run from a source tree
        return 'source'


@functools.lru_cache(maxsize=None)
def core_stamp(folders: tuple[Path, ...] = CORE) -> str:
    """
    Return a hash of the package version and of the code of every ``.py`` file in folders.

    Parsing the core takes a few hundred milliseconds, so the result is kept in a small file
    named by a hash of the files' bytes (which determine it) beside the kernels' cache, and
    read from there by later processes.
    """
    sources = _sources(folders)
    raw = hashlib.sha256(_version().encode())
    for name, data in sources:
        raw.update(name.encode())
        raw.update(data)
    memo = _memo_folder() / f'trajplan_core_stamp_{raw.hexdigest()[:32]}'
    try:
        kept = memo.read_text(encoding='ascii')
        if len(kept) == 64:
            return kept
    except (OSError, UnicodeDecodeError):
        pass
    digest = hashlib.sha256(_version().encode())
    for name, data in sources:
        digest.update(name.encode())
        digest.update(_code(data, name).encode())
    stamp = digest.hexdigest()
    try:                                     # whole or not at all: another process may read
        memo.parent.mkdir(parents=True, exist_ok=True)
        part = memo.with_name(f'{memo.name}.{os.getpid()}')
        part.write_text(stamp, encoding='ascii')
        os.replace(part, memo)
    except OSError:                          # nowhere to keep it: parsed again next time
        pass
    return stamp


def _sources(folders: tuple[Path, ...]) -> list[tuple[str, bytes]]:
    """Return every ``.py`` file under ``folders``: its name there and bytes, in a fixed order."""
    return [(str(path.relative_to(folder.parent)), path.read_bytes())
            for folder in folders for path in sorted(folder.rglob('*.py'))]


def _memo_folder() -> Path:
    """Return where ``core_stamp`` keeps its result: the kernels' cache folder if one is set."""
    return Path(numba.config.CACHE_DIR or CORE[0].parent / '__pycache__')


def _code(source: bytes, name: str) -> str:
    """Return a file's syntax tree without docstrings (comments are not in it), as text."""
    tree = ast.parse(source, filename=name)
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            first = node.body[0] if node.body else None
            if (isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant)
                    and isinstance(first.value.value, str)):
                node.body = node.body[1:] or [ast.Pass()]
    return ast.dump(tree)


class _CoreStamped:
    """
    A numba cache locator whose source stamp is the whole core's (``core_stamp``).

    In a cache folder outside the package, a module's kernels are kept under its folder's name
    and the stamp (``trajplan_ros_planning_<stamp>``), not under a hash of where the package is
    installed: copies of the same sources (a venv, a colcon install) share one cache there, and
    copies of different sources do not take turns overwriting it.
    """

    def get_source_stamp(self) -> str:
        return core_stamp()

    def get_disambiguator(self) -> str:
        """Name the cache file by the kernel's module and name alone, not its line."""
        return 'kernel'

    @classmethod
    def get_suitable_cache_subpath(cls, py_file: str) -> str:
        return f'trajplan_ros_{Path(py_file).parent.name}_{core_stamp()[:16]}'


class UserProvidedLocator(_CoreStamped, caching.UserProvidedCacheLocator):
    """``NUMBA_CACHE_DIR``, core-stamped."""


class InTreeLocator(_CoreStamped, caching.InTreeCacheLocator):
    """The package's ``__pycache__``, core-stamped."""


class UserWideLocator(_CoreStamped, caching.UserWideCacheLocator):
    """The user's cache folder, core-stamped."""


class _KernelCacheImpl(caching.CompileResultCacheImpl):
    _locator_classes = [UserProvidedLocator, InTreeLocator, UserWideLocator]


class _KernelCache(caching.FunctionCache):
    _impl_class = _KernelCacheImpl


def kernel(func: Callable[..., Any]) -> Any:
    """Compile ``func`` with numba: no GIL, cached on disk where any cache folder is writable."""
    return _compiled(func, 'never')


def inlined_kernel(func: Callable[..., Any]) -> Any:
    """
    ``kernel``, but inlined into the kernels that call it, not compiled on its own for them.

    numba builds every kernel called from another as a library of its own, and optimises each
    caller's machine code anew with all its callees linked in: a helper called by one kernel
    only (a step of that kernel's computation) would cost seconds of compile for nothing.
    Keep inlining one level deep: numba inlines by copying the callee's code into the caller
    block by block, each copy with the caller's whole scope, so inlined kernels that inline
    others into large callers cost minutes (the convex bounds nested three deep: 436 s).
    """
    return _compiled(func, 'always')


def _compiled(func: Callable[..., Any], inline: str) -> Any:
    compiled = numba.njit(nogil=True, inline=inline)(func)
    try:
        compiled._cache = _KernelCache(func)       # what njit(cache=True) does, core-stamped
    except RuntimeError as exc:                 # numba: "cannot cache ...: no locator available"
        if 'no locator available' not in str(exc):
            raise
        if not _warned:
            _warned.append(True)
            _LOG.warning('trajplan_ros: no writable cache folder for the compiled kernels, so '
                         'every process compiles them anew; set NUMBA_CACHE_DIR to a writable '
                         'folder to keep them')
    _compile_calls_unliteral(compiled)
    _compile_claimed(compiled)
    _KERNELS.append(compiled)
    return compiled


def _compile_claimed(compiled: Any) -> None:
    """Compile ``compiled`` holding its claim, while a helper process compiles beside."""
    original = compiled.compile

    def compile_claimed(sig: Any) -> Any:
        args = tuple(sigutils.normalize_signature(sig)[0])
        if args in compiled.overloads:
            return original(sig)
        with parallel_compile.claim(compiled, args):
            return original(sig)
    compiled.compile = compile_claimed


def _compile_calls_unliteral(compiled: Any) -> None:
    """
    Let calls from other kernels compile ``compiled`` for their argument types, not values.

    numba compiles a kernel called with a constant (``tool_rows(chain, x, True)``) for that
    value: once for True, once for False and once more for a bool from Python, each a cold
    compile of seconds. One compiled version for each type serves every call.
    """
    template = compiled.get_call_template

    def get_call_template(args: tuple, kws: dict) -> Any:
        return template(tuple(types.unliteral(a) for a in args),
                        {k: types.unliteral(v) for k, v in kws.items()})
    compiled.get_call_template = get_call_template


def kernels() -> tuple[Any, ...]:
    """Return every kernel defined so far."""
    return tuple(_KERNELS)


@dataclass(frozen=True)
class Warmup:
    """
    What ``warm_up`` did: its time (s) and how many kernels it compiled or loaded.

    ``helped`` is whether a helper process compiled beside it; the kernels it loaded then are
    mostly the helper's.
    """

    seconds: float
    compiled: int
    loaded: int
    helped: bool = False

    def describe(self) -> str:
        """Say it in one line, for a log."""
        if self.compiled and self.helped:
            return (f'compiled {self.compiled + self.loaded} planning kernels in '
                    f'{self.seconds:.1f} s on two cores ({self.loaded} of them loaded from what '
                    'a helper process compiled beside; once: later starts load them from the '
                    'cache)')
        if self.compiled:
            return (f'compiled {self.compiled} planning kernels in {self.seconds:.1f} s (once: '
                    'later starts load them from the cache)')
        return f'loaded {self.loaded} compiled planning kernels in {self.seconds:.2f} s'


def warm_up(run: Callable[[], object],
            announce: Callable[[str], object] | None = None,
            recorded: str = 'first_plan') -> Warmup:
    """
    Call ``run`` (which calls kernels) and count what it compiled or loaded.

    A kernel's new machine code is either loaded (numba's cache hits) or compiled. When the
    first compile begins, ``announce`` is told so, with how long compiling takes, and a helper
    process begins to compile the ``recorded`` run's kernels from its end
    (``parallel_compile``), until ``run`` returns.
    """
    def loaded() -> int:
        return sum(sum(k.stats.cache_hits.values()) for k in _KERNELS)

    overloads, hits = {k: len(k.overloads) for k in _KERNELS}, loaded()
    helper = parallel_compile.Helper(recorded)
    began = time.perf_counter()
    try:
        with event.install_listener('numba:compile', _FirstCompile(announce, helper)):
            run()
    finally:
        helped = helper.stop()
    seconds = time.perf_counter() - began
    new = sum(len(k.overloads) - overloads[k] for k in _KERNELS)
    from_cache = loaded() - hits
    return Warmup(seconds, new - from_cache, from_cache, helped)


class _FirstCompile(event.Listener):
    """
    Say once when numba begins to compile, and start the helper process then.

    A kernel found on disk is loaded silently.
    """

    def __init__(self, announce: Callable[[str], object] | None,
                 helper: parallel_compile.Helper) -> None:
        self._announce = announce
        self._helper = helper

    def on_start(self, ev: event.Event) -> None:
        self._helper.start(ev.data['dispatcher'])
        if self._announce is not None:
            self._announce(f'compiling planning kernels for the first time: {FIRST_COMPILE} '
                           '(later starts load them in about a second)')
            self._announce = None

    def on_end(self, _: event.Event) -> None:
        pass
