# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
``trajplan demo`` waits for a node that says it is compiling, however long past its timeout.

The node here is a stand-in process that logs as planner_node does on a first start (a
``compiling`` line, later ``compiled`` and ``ready``), so that a compile of minutes takes none.
"""
from __future__ import annotations

from pathlib import Path
import sys
import threading

from node_under_test import LIVENESS_S
import pytest
from trajplan_ros.tools.demo import _wait_until_ready
from trajplan_ros.tools.node_process import PlannerProcess

#: Logs like a first start, and finishes "compiling" once the file argv[1] exists.
FIRST_START = """
import pathlib, sys, threading
print('[INFO] [1.0] [trajplan]: compiling 63 planning kernels for the first time: about a minute')
while not pathlib.Path(sys.argv[1]).exists():
    threading.Event().wait(0.01)
print('[INFO] [2.0] [trajplan]: compiled 63 planning kernels in 61.0 s (once: later starts load')
print('[INFO] [2.0] [trajplan]: ready: the paper arm')
"""


def test_the_demo_waits_for_a_compiling_node_past_its_timeout(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture
                                                              ) -> None:
    done = tmp_path / 'compiled'
    node = PlannerProcess(argv=[sys.executable, '-c', FIRST_START, str(done)])
    failure: list[BaseException] = []

    def wait() -> None:
        try:
            _wait_until_ready(node, timeout=LIVENESS_S)
        except BaseException as exc:  # noqa: BLE001 - reported by the test
            failure.append(exc)

    try:
        assert node.wait_for('compiling', LIVENESS_S)
        waiting = threading.Thread(target=wait)
        waiting.start()
        waiting.join(timeout=0.5)
        assert waiting.is_alive() and not failure      # still waiting: the compile goes on
        done.touch()
        waiting.join(timeout=LIVENESS_S)
        assert not waiting.is_alive() and not failure, failure
        assert node.proc.wait(timeout=LIVENESS_S) == 0
    finally:
        node.stop()
    out = capsys.readouterr().out
    assert 'planner_node: compiling 63 planning kernels for the first time' in out, out
    assert 'planner_node: compiled 63 planning kernels in 61.0 s' in out, out


def test_the_demo_gives_up_on_a_node_that_dies_while_compiling() -> None:
    script = "print('[INFO] [1.0] [trajplan]: compiling 63 planning kernels'); raise SystemExit(3)"
    node = PlannerProcess(argv=[sys.executable, '-c', script])
    try:
        with pytest.raises(TimeoutError, match='exited with code 3 while compiling'):
            _wait_until_ready(node, timeout=LIVENESS_S)
    finally:
        node.stop()
