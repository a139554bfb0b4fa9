# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
How many planned profile motions joint_trajectory_controller follows within every limit.

A benchmark, not a test (pytest does not collect it): ``N`` plans of an arm from seeded random
goals and starts, the four profile/timing pairs of ``test_profile_trajectory.profiles`` in turn,
each successful plan's message checked by ``check_under_the_controller`` (velocity and
acceleration within the limits to 1e-6, jerk to 1e-3, under the controller's interpolation).
From the repository root, with the ``test`` extra installed::

    .venv/bin/python test/controller_check.py so101 10000 51
"""
from __future__ import annotations

from collections import Counter
from pathlib import Path
import sys

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from test_profile_trajectory import arm_of, check_under_the_controller, profiles  # noqa: E402
from trajplan_ros import plan  # noqa: E402


def main(name: str, count: int, seed: int) -> None:
    """Plan ``count`` goals of arm ``name`` from ``seed``; print the failures by profile."""
    arm = arm_of(name)
    pairs = list(profiles(name).items())
    rng = np.random.default_rng(seed)
    planned, failed = Counter(), Counter()
    for k in range(count):
        q, start = rng.uniform(arm.lower, arm.upper, (2, arm.n_joints))
        label, profile = pairs[k % len(pairs)]
        result = plan(arm.tool(q[None])[0][0], start, arm=arm, omega=100.0, profile=profile,
                      seed=k)
        if not result.success:
            continue
        planned[label] += 1
        law = profile.time_law(arm, 100.0)
        try:
            check_under_the_controller(result.start, result.joint_goal, law, profile.timing,
                                       arm.joint_names)
        except AssertionError:
            failed[label] += 1
    for label, _ in pairs:
        print(f'{name} {label}: {failed[label]} of {planned[label]} plans over a limit')
    print(f'{name}: {sum(failed.values())} of {sum(planned.values())} plans over a limit '
          f'(seed {seed})')


if __name__ == '__main__':
    main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]))
