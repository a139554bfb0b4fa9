# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Third-party modules imported on first use: a feature's libraries cost only where it is used.

coal, trimesh (with scipy and networkx) and yourdfpy (with lxml) hold about 120 MB between them;
a node planning the paper's arm without a scene uses none of them. ``trimesh = lazy('trimesh')``
at the top of a module reads as an import and costs nothing until the first
``trimesh.something``, which imports it.

Not the standard library's ``LazyLoader``: that puts the module into ``sys.modules`` at once,
and anything that walks ``sys.modules`` (rclpy's logger does, through ``inspect.getmodule``)
imports it there.
"""
from __future__ import annotations

import importlib
import importlib.util
from typing import Any

__all__ = ['lazy']


class _LazyModule:
    """Stands for a module until an attribute is read; then holds the module's names."""

    def __init__(self, name: str) -> None:
        self.__dict__['_name'] = name

    def __getattr__(self, attr: str) -> Any:
        """Import the module (once), keep its names for the next reads, return ``attr``."""
        module = importlib.import_module(self.__dict__['_name'])
        self.__dict__.update(vars(module))
        return getattr(module, attr)

    def __repr__(self) -> str:
        return f"<module {self.__dict__['_name']!r}, imported on first use>"


def lazy(name: str) -> Any:
    """Return a stand-in for module ``name`` that imports it when an attribute is first read."""
    if importlib.util.find_spec(name) is None:
        raise ModuleNotFoundError(f'No module named {name!r}', name=name)
    return _LazyModule(name)
