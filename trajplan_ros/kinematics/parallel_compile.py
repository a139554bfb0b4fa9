# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Compiling the kernels on two cores: a helper process works from the other end.

numba compiles in one thread, and a first plan compiles its kernels one after another (about
40 s for the paper's arm). When a warm-up begins to compile, it starts a helper process that
compiles the same kernels in the reverse of the order a plan needs them, from a recorded list
(``kernel_order.json``: each kernel and its argument types, in the order a first plan on an
empty cache finished compiling them). Both save to the one disk cache. A lock file per kernel
and signature keeps the two from compiling one twice: whoever takes it compiles, the other
waits and loads the result from the cache, or in the helper's case goes on to the next one.
The warm-up stops the helper when it is done; the helper also ends when its parent does.

Without a cache folder, file locks or the list, the warm-up compiles alone.
``python -m trajplan_ros.tools.kernel_order`` records the list anew (on an empty cache of its
own, about a minute); ``test_kernels`` checks that a first plan's kernels are in it.
"""
from __future__ import annotations

import base64
from contextlib import contextmanager
import functools
import hashlib
import importlib
import json
import os
from pathlib import Path
import pickle
import subprocess
import sys
import threading
import time
from typing import Any, Iterator

try:
    import fcntl
except ImportError:                               # not on Windows: compile alone there
    fcntl = None

__all__ = ['ALONE', 'ORDER', 'RUNS', 'Helper', 'claim', 'compile_backwards', 'recorded']

#: Each kernel's signatures, in the order a first plan finished compiling them.
ORDER = Path(__file__).with_name('kernel_order.json')
#: The recorded runs: a plan of the default request, and every kind of plan (``prepare()``).
RUNS = ('first_plan', 'every_plan')
#: How long a process waits for another's compile of one kernel before compiling it itself.
WAIT_S = 600.0
#: Set (to anything) to compile in one process, as the recording (tools.kernel_order) does.
ALONE = 'TRAJPLAN_COMPILE_ALONE'
_active: list[bool] = []
_held: set[Path] = set()                    # this process's locks (flock is per open file)


@functools.lru_cache(maxsize=None)
def recorded(run: str) -> tuple[tuple[str, str, tuple], ...]:
    """
    Return the kernels that ``run`` compiles, in order: module, name and argument types.

    Entries this numba cannot read (another release's types) are left out.
    """
    try:
        listed = json.loads(ORDER.read_text(encoding='utf-8'))[run]
    except (OSError, ValueError, KeyError):
        return ()
    found = []
    for module, name, types in listed:
        try:
            found.append((module, name, pickle.loads(base64.b64decode(types))))
        except Exception:                         # noqa: B902 (any unpickling error: skip it)
            continue
    return tuple(found)


def _lock_path(kernel: Any, args: tuple) -> Path:
    """Return the lock file of one kernel and signature, beside the kernel's cache."""
    key = hashlib.sha256(str(args).encode()).hexdigest()[:16]
    folder = Path(kernel.stats.cache_path) / 'claims'
    return folder / f'{kernel.py_func.__module__}.{kernel.py_func.__qualname__}.{key}.lock'


@contextmanager
def claim(kernel: Any, args: tuple, wait: bool = True) -> Iterator[bool]:
    """
    Hold the lock on compiling ``kernel`` for ``args`` while two processes compile.

    Yields whether it is held: with ``wait``, after the other process has compiled it (it is
    then loaded from the cache), or after ``WAIT_S``; without, at once (False if the other
    process holds it). Outside a parallel compile, yields True at once.
    """
    if not _active or fcntl is None or not kernel.stats.cache_path:
        yield True
        return
    path = _lock_path(kernel, args)
    if path in _held:                            # a compile inside this one's (a callee's)
        yield True
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        lock = os.open(path, os.O_RDONLY | os.O_CREAT, 0o644)
    except OSError:                              # no lock to be had: compile without one
        yield True
        return
    try:
        deadline = time.monotonic() + (WAIT_S if wait else 0.0)
        while True:
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:              # the other process holds it
                if time.monotonic() >= deadline:
                    yield wait
                    return
                time.sleep(0.02)
            except OSError:                      # flock not offered here: compile without it
                yield True
                return
        _held.add(path)
        try:
            yield True
        finally:
            _held.discard(path)
            fcntl.flock(lock, fcntl.LOCK_UN)
    finally:
        os.close(lock)


class Helper:
    """The helper process of one warm-up: started at its first compile, stopped at its end."""

    def __init__(self, run: str) -> None:
        self._run = run
        self._process: subprocess.Popen | None = None

    def start(self, kernel: Any) -> None:
        """Start the helper, once, if ``kernel`` (the first one compiled) has a disk cache."""
        if (self._process is not None or fcntl is None or not kernel.stats.cache_path
                or os.environ.get(ALONE) or not recorded(self._run)):
            return
        root = str(Path(__file__).resolve().parents[2])       # this copy of the package
        run = self._run
        path = os.environ.get('PYTHONPATH')
        env = {**os.environ, 'PYTHONPATH': root + (os.pathsep + path if path else '')}
        try:
            self._process = subprocess.Popen(
                [sys.executable, '-c',
                 f'import {__name__} as p; p.compile_backwards({run!r}, {os.getpid()})'],
                env=env,
                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        except OSError:
            return
        _active[:] = [True]

    def stop(self) -> bool:
        """Stop the helper, if started (what it compiled is on disk); return whether it was."""
        _active.clear()
        if self._process is None:
            return False
        self._process.kill()
        self._process.wait()
        self._process = None
        return True


def compile_backwards(run: str, parent: int) -> None:
    """Compile ``run``'s kernels from the last (skipping those held) while ``parent`` lives."""
    _active[:] = [True]

    def orphaned() -> None:                        # its parent gone (killed), end at once
        while os.getppid() == parent:
            time.sleep(0.2)
        os._exit(0)

    threading.Thread(target=orphaned, daemon=True).start()
    for module, name, args in reversed(recorded(run)):
        kernel = getattr(importlib.import_module(module), name, None)
        if kernel is None or tuple(args) in kernel.overloads:
            continue
        with claim(kernel, args, wait=False) as mine:
            if mine:
                kernel.compile(args)
