# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
ament_flake8 with ROS's configuration, as the ament_python template runs it.

flake8 runs quietly without its plugins, so a second test feeds it a file that breaks one rule
of each plugin ROS's configuration relies on and checks that every one is reported.
"""
from pathlib import Path

from ament_flake8.main import main_with_errors
import pytest

REPO = Path(__file__).resolve().parents[1]
SOURCES = [str(REPO / 'trajplan_ros'), str(REPO / 'test'), str(REPO / 'setup.py')]

#: One finding per plugin that ROS's flake8 configuration expects: code -> a line breaking it.
PLUGIN_PROBES = {
    'Q000': 'name = "double quotes"',                          # flake8-quotes
    'I100': 'import sys\nimport os',                           # flake8-import-order
    'A001': 'list = [1]',                                      # flake8-builtins
    'C408': 'empty = dict()',                                  # flake8-comprehensions
    'D401': 'def probe():\n    """Returns nothing."""',        # flake8-docstrings
}


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8() -> None:
    rc, errors = main_with_errors(argv=SOURCES)
    assert rc == 0, f'Found {len(errors)} code style errors / warnings:\n' + '\n'.join(errors)


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8_plugins_are_loaded(tmp_path: Path) -> None:
    probe = tmp_path / 'probe.py'
    probe.write_text("'''Probe.'''\n" + '\n'.join(PLUGIN_PROBES.values()) + '\n',
                     encoding='utf-8')
    rc, errors = main_with_errors(argv=[str(probe)])
    assert rc == 1
    found = {error.split(': ')[1].split()[0] for error in errors}
    assert set(PLUGIN_PROBES) <= found, f'not reported: {set(PLUGIN_PROBES) - found}'
