# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Libraries load by feature: coal, trimesh and yourdfpy only where a plan or an arm uses them."""
import subprocess
import sys

import pytest
from trajplan_ros.kinematics.lazy_modules import lazy

#: The collision and URDF libraries, and what they bring.
HEAVY = ('coal', 'trimesh', 'yourdfpy', 'lxml', 'networkx')
#: Prints which of ``HEAVY`` a process has imported after running the code before it.
REPORT = f'import sys; print(sorted(m for m in {HEAVY!r} if m in sys.modules))'


def imported_after(code: str) -> str:
    """Return the heavy modules imported by a new process after ``code``."""
    done = subprocess.run([sys.executable, '-c', f'{code}\n{REPORT}'], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout.strip().splitlines()[-1]


def test_a_plan_without_a_scene_imports_no_collision_or_urdf_library() -> None:
    code = ('import inspect, trajplan_ros.ros.node\n'
            'from trajplan_ros import plan\n'
            'inspect.getmodule(plan)\n'               # walks sys.modules, as rclpy's logger
            'assert plan((0.2, 0.1, 0.15), seed=0).success')
    assert imported_after(code) == '[]'


def test_a_scene_and_a_urdf_import_them() -> None:
    code = ('from trajplan_ros import ArmCollision, paper_arm\n'
            'from trajplan_ros.kinematics.urdf_export import urdf_xml\n'
            'ArmCollision.from_urdf(urdf_xml(paper_arm(), velocity=0.2).encode(), paper_arm())')
    assert imported_after(code) == str(sorted(HEAVY))


def test_the_stand_in_imports_on_first_read_and_then_holds_the_names() -> None:
    json = lazy('json')
    assert json.dumps([1]) == '[1]'
    assert 'loads' in vars(json)
    with pytest.raises(ModuleNotFoundError, match="No module named 'no_such_module_here'"):
        lazy('no_such_module_here')
