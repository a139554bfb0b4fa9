# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Record the order a first plan compiles its kernels in, for the helper process (parallel_compile).

``python -m trajplan_ros.tools.kernel_order`` plans, in a new process on an empty kernel cache
of its own and compiling alone, the default request and then every kind of plan
(``prepare()``), and writes each kernel as it finished compiling, with its argument types, to
``trajplan_ros/kinematics/kernel_order.json``. Run it when a kernel's argument types change
(``test_kernels`` says so); it takes about a minute.
"""
from __future__ import annotations

import base64
import json
import os
import pickle
import subprocess
import sys
import tempfile

from numba.core import event
from trajplan_ros.kinematics.jit import kernels
from trajplan_ros.kinematics.parallel_compile import ALONE, ORDER
from trajplan_ros.planning.planner import _WARM_UP_GOAL, prepare
from trajplan_ros.planning.request import PlanRequest

__all__ = ['main']


class _Finished(event.Listener):
    """Lists each kernel of the core as it finishes compiling: module, name, argument types."""

    def __init__(self) -> None:
        self.done: list[list[str]] = []

    def on_start(self, _: event.Event) -> None:
        pass

    def on_end(self, ev: event.Event) -> None:
        kernel = ev.data['dispatcher']
        if kernel in kernels():
            types = pickle.dumps(tuple(ev.data['args']))
            self.done.append([kernel.py_func.__module__, kernel.py_func.__qualname__,
                              base64.b64encode(types).decode()])


def _record_here() -> None:
    finished = _Finished()
    order = {}
    with event.install_listener('numba:compile', finished):
        prepare(PlanRequest(_WARM_UP_GOAL))
        order['first_plan'] = list(finished.done)
        prepare()
        order['every_plan'] = list(finished.done)
    ORDER.write_text(json.dumps(order, indent=0) + '\n', encoding='utf-8')


def main() -> None:
    """Record ``ORDER`` in a new process: the kernels' cache is set before numba loads."""
    if os.environ.get(ALONE) == 'record':
        _record_here()
        return
    with tempfile.TemporaryDirectory(prefix='trajplan-record-') as cache:
        env = {**os.environ, 'NUMBA_CACHE_DIR': cache, ALONE: 'record'}
        subprocess.run([sys.executable, '-m', 'trajplan_ros.tools.kernel_order'], env=env,
                       check=True)


if __name__ == '__main__':
    main()
