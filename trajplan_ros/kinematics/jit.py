# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
How the planning core compiles its kernels: numba's ``njit``, with one cache policy.

Every kernel is ``@kernel``: compiled by numba with ``nogil=True`` (the node's executor thread
runs while a plan computes) and ``cache=True``, so that a process after the first loads the
machine code from disk instead of compiling it. numba keeps the cache beside the source (the
package's ``__pycache__``), else in the user's cache folder (``NUMBA_CACHE_DIR``, or
``~/.cache``); where neither is writable it cannot cache at all, and the kernels are then
compiled in every process, with one warning saying how to set ``NUMBA_CACHE_DIR``.

numba drops a cached kernel when its own source file changes, but not when a kernel it calls
in another file does, and it freezes the globals a kernel reads. So a kernel calls only kernels
of its own file and reads only constants of its own file (a test holds the package to that),
and a changed kernel can never run stale.

``warm_up`` compiles or loads every kernel once, so that no plan pays for it; it reports how
long that took and whether anything had to be compiled.
"""
from __future__ import annotations

from dataclasses import dataclass
import logging
import time
from typing import Any, Callable

import numba

__all__ = ['Warmup', 'kernel', 'kernels', 'warm_up']

_LOG = logging.getLogger('trajplan_ros')
#: Every kernel made by ``kernel``, with the call that compiles it (see ``warm_up``).
_KERNELS: list[Any] = []
_warned: list[bool] = []


def kernel(func: Callable[..., Any]) -> Any:
    """Compile ``func`` with numba: no GIL, cached on disk where any cache folder is writable."""
    try:
        compiled = numba.njit(cache=True, nogil=True)(func)
    except RuntimeError as exc:                 # numba: "cannot cache ...: no locator available"
        if 'no locator available' not in str(exc):
            raise
        if not _warned:
            _warned.append(True)
            _LOG.warning('trajplan_ros: no writable cache folder for the compiled kernels, so '
                         'every process compiles them anew; set NUMBA_CACHE_DIR to a writable '
                         'folder to keep them')
        compiled = numba.njit(nogil=True)(func)
    _KERNELS.append(compiled)
    return compiled


def kernels() -> tuple[Any, ...]:
    """Return every kernel defined so far."""
    return tuple(_KERNELS)


@dataclass(frozen=True)
class Warmup:
    """What ``warm_up`` did: its time (s) and how many kernels it compiled or loaded."""

    seconds: float
    compiled: int
    loaded: int

    def describe(self) -> str:
        """Say it in one line, for a log."""
        if self.compiled:
            return (f'compiled {self.compiled} planning kernels in {self.seconds:.1f} s (once: '
                    'later starts load them from the cache)')
        return f'loaded {self.loaded} compiled planning kernels in {self.seconds:.2f} s'


def warm_up(run: Callable[[], object]) -> Warmup:
    """
    Call ``run`` (which calls every kernel once) and count what it compiled or loaded.

    A kernel's new machine code is either loaded (numba's cache hits) or compiled.
    """
    def loaded() -> int:
        return sum(sum(k.stats.cache_hits.values()) for k in _KERNELS)

    overloads, hits = {k: len(k.overloads) for k in _KERNELS}, loaded()
    began = time.perf_counter()
    run()
    seconds = time.perf_counter() - began
    new = sum(len(k.overloads) - overloads[k] for k in _KERNELS)
    from_cache = loaded() - hits
    return Warmup(seconds, new - from_cache, from_cache)
