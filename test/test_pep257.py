# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""ament_pep257 (docstring conventions, ROS's selection), as the ament_python template runs it."""
from pathlib import Path

from ament_pep257.main import main
import pytest

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257() -> None:
    rc = main(argv=[str(REPO / 'trajplan_ros'), str(REPO / 'test'), str(REPO / 'setup.py')])
    assert rc == 0, 'Found code style errors / warnings'
