# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Another version of this package as a row of the benchmark: ``trajplan bench --baseline DIR``.

DIR is a source tree of that version, for example the numpy core before the compiled kernels:
``git worktree add /tmp/trajplan-numpy 56ebf49``. The row plans the same goals from the same
starts with the same seeds as the other rows, in turn with them, in a child process that imports
the package from DIR (the same Python and venv); the child times each ``plan`` call as this
process times its own rows (``time.perf_counter`` around the call, objective included), so the
pipe between the two costs the row nothing (it plans once, untimed, for each arm first, as this
process compiles or loads its kernels first). The arm goes to the child as its arrays, so that
every version plans exactly this arm; only the API the versions share is used: ``ArmModel``'s
constructor and ``plan(goal, start, arm=, mode=, seed=)`` (and ``orientation=`` for a pose,
which only versions that plan poses take, and the tolerances given).
"""
from __future__ import annotations

import json
import os
from pathlib import Path
import subprocess
import sys
from typing import Any, Mapping

import numpy as np

from trajplan_ros.kinematics import ArmModel
from trajplan_ros.motion.motion_profile import MotionProfile
from trajplan_ros.search.goal import Mode
from trajplan_ros.search.objective import planned_arm
from trajplan_ros.tools.bench.methods import Answer, Method

__all__ = ['baseline_method']

#: The child: reads one JSON request a line (an arm, or a goal to plan), answers one a line.
_CHILD = """
import json, sys, time
import numpy as np
import trajplan_ros
from trajplan_ros import ArmModel, plan
print(json.dumps({'package': trajplan_ros.__file__}), flush=True)
arm = None
for line in sys.stdin:
    request = json.loads(line)
    if 'arm' in request:
        spec = request['arm']
        arm = ArmModel(np.array(spec.pop('rotations')), np.array(spec.pop('translations')),
                       base=np.array(spec.pop('base')), **spec)
        plan(arm.tool(np.zeros((1, arm.n_joints)))[0][0] * 0.9, arm=arm, seed=0)  # warm, untimed
        print(json.dumps({}), flush=True)
        continue
    clock = time.perf_counter()
    given = {k: request[k] for k in ('orientation', 'tolerance', 'axis_tolerance',
                                     'orientation_tolerance') if k in request}
    result = plan(request['goal'], request['start'], arm=arm, mode=request['mode'],
                  seed=request['seed'], **given)
    seconds = time.perf_counter() - clock
    joints = None if result.joint_goal is None else result.joint_goal.tolist()
    print(json.dumps({'joints': joints, 'seconds': seconds, 'message': result.message}),
          flush=True)
"""


def _arm_spec(arm: ArmModel) -> dict[str, Any]:
    """Return the arm as the arrays of ``ArmModel``'s constructor (JSON keeps every float)."""
    return {'rotations': arm.rotations.tolist(), 'translations': arm.translations.tolist(),
            'base': arm.base.tolist(), 'tool_point': arm.tool_point.tolist(),
            'tool_axis': arm.tool_axis.tolist(), 'sign': arm.sign.tolist(),
            'offset': arm.offset.tolist(), 'lower': arm.lower.tolist(),
            'upper': arm.upper.tolist(), 'velocity': arm.velocity.tolist(),
            'joint_names': list(arm.joint_names), 'planned': arm.planned,
            'base_link': arm.base_link, 'tip_link': arm.tip_link}


class _Child:
    """The other version's planner in a child process, for one arm at a time."""

    def __init__(self, directory: Path) -> None:
        env = {**os.environ, 'PYTHONPATH': os.pathsep.join(
            filter(None, [str(directory), os.environ.get('PYTHONPATH')]))}
        self._proc = subprocess.Popen([sys.executable, '-c', _CHILD], cwd=directory, env=env,
                                      stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        try:
            package = Path(self._ask(None)['package']).resolve()
        except RuntimeError as exc:                    # it could not import the package
            raise ValueError(f'--baseline {directory}: {exc}') from None
        if directory not in package.parents:
            self._proc.kill()
            raise ValueError(f'--baseline {directory}: the child imported {package}, not the '
                             'package in that folder')
        self._arm: ArmModel | None = None

    def _ask(self, request: dict[str, Any] | None) -> dict[str, Any]:
        if request is not None:
            self._proc.stdin.write(json.dumps(request) + '\n')
            self._proc.stdin.flush()
        line = self._proc.stdout.readline()
        if not line:
            raise RuntimeError(f'the baseline process ended (exit code {self._proc.wait()})')
        return json.loads(line)

    def solve(self, arm: ArmModel, mode: Mode, goal: np.ndarray, start: np.ndarray,
              seed: int, profile: MotionProfile, orientation: np.ndarray | None = None,
              tolerances: Mapping[str, float] | None = None) -> Answer:
        """
        Plan ``goal`` from ``start`` in the child; the answer carries the child's time.

        The child plans the servo law whatever ``profile`` (an older version may know no other):
        its row is there for the plan time.
        """
        if arm is not self._arm:
            self._ask({'arm': _arm_spec(arm)})
            self._arm = arm
        request = {'goal': np.asarray(goal, float).tolist(),
                   'start': np.asarray(start, float).tolist(), 'mode': mode.value,
                   'seed': int(seed)}
        if orientation is not None:
            request['orientation'] = np.asarray(orientation, float).tolist()
        request.update(tolerances or {})
        answer = self._ask(request)
        if answer['joints'] is None:
            raise ValueError(f"the baseline rejected goal {list(goal)}: {answer['message']}")
        joints = np.array(answer['joints'])
        planned = planned_arm(arm, mode).planned
        return Answer(joints[:planned], joints=joints, seconds=answer['seconds'])


def baseline_method(directory: str) -> Method:
    """Return the row ``baseline``: IEPSO of the version in ``directory`` (module docstring)."""
    folder = Path(directory).resolve()
    if not (folder / 'trajplan_ros' / '__init__.py').is_file():
        raise ValueError(f'--baseline {directory}: no trajplan_ros package in that folder (give '
                         'a source tree, e.g. git worktree add DIR 56ebf49)')
    return Method('baseline', f'IEPSO of the version in {folder}', _Child(folder).solve)
