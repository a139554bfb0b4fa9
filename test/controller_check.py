# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
How many published motions joint_trajectory_controller follows within every limit.

A benchmark, not a test (pytest does not collect it). From the repository root, with the
``test`` extra installed (the package is taken from this tree, not from an installed copy)::

    .venv/bin/python test/controller_check.py so101 10000 51
    .venv/bin/python test/controller_check.py random so101 20000 61

The first plans ``N`` seeded random goals and starts of an arm, the four profile/timing pairs
of ``test_profile_trajectory.profiles`` in turn, and checks each successful plan's message with
``check_under_the_controller`` (velocity and acceleration within the limits to 1e-6, jerk to
1e-3, under the controller's interpolation, sampled at 1 ms and at every segment's ends).

The second (``random``) draws, for each law (servo, trapezoidal, jerk-limited) and timing
(independent, synchronized), ``N`` moves on per-joint limits log-uniform over four decades
(``controller_limits.random_law`` and ``random_move``) of an arm (``so101``, ``panda``, any
other of ``published_arms``, or ``paper``), and computes each message's peaks under the
controller (``controller_limits.controller_peaks``: every segment's polynomial as the
controller computes it, its extremes). It prints how many exceed a limit, the worst peak per
limit and how much longer than the fastest (R) the published motion is.
"""
from __future__ import annotations

from collections import Counter
from pathlib import Path
import sys

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]

from controller_limits import controller_peaks, peaks, random_law, random_move  # noqa: E402
import numpy as np  # noqa: E402
from profile_cases import arm_of, check_under_the_controller, profiles  # noqa: E402
from trajplan_ros import paper_arm, plan  # noqa: E402
from trajplan_ros.motion.motion_profile import Timing  # noqa: E402
from trajplan_ros.motion.time_law import JERK_LIMITED, SERVO, TRAPEZOIDAL  # noqa: E402

LAWS = {'servo': SERVO, 'trapezoidal': TRAPEZOIDAL, 'jerk_limited': JERK_LIMITED}


def planned(name: str, count: int, seed: int) -> None:
    """Plan ``count`` goals of arm ``name`` from ``seed``; print the failures by profile."""
    arm = arm_of(name)
    pairs = list(profiles(name).items())
    rng = np.random.default_rng(seed)
    done, failed, worst = Counter(), Counter(), {label: np.zeros(3) for label, _ in pairs}
    for k in range(count):
        q, start = rng.uniform(arm.lower, arm.upper, (2, arm.n_joints))
        label, profile = pairs[k % len(pairs)]
        result = plan(arm.tool(q[None])[0][0], start, arm=arm, angular_velocity=100.0,
                      motion=profile, seed=k)
        if not result.success:
            continue
        done[label] += 1
        law = profile.time_law(arm, 100.0)
        worst[label] = np.maximum(worst[label], controller_peaks(result.trajectory(arm), law))
        try:
            check_under_the_controller(result.start, result.joint_goal, law, profile.timing,
                                       arm.joint_names)
        except AssertionError:
            failed[label] += 1
    for label, _ in pairs:
        print(f'{name} {label}: {failed[label]} of {done[label]} plans over a limit; '
              f'worst peak / limit: {_ratios(worst[label])}')
    print(f'{name}: {sum(failed.values())} of {sum(done.values())} plans over a limit '
          f'(seed {seed})')


def random_moves(name: str, count: int, seed: int) -> None:
    """Check ``count`` random moves on random limits per law and timing of arm ``name``."""
    arm = paper_arm() if name == 'paper' else arm_of(name)
    over_all = total = 0
    for law_name, kind in LAWS.items():
        for timing in Timing:
            rng = np.random.default_rng([seed, kind, timing is Timing.SYNCHRONIZED])
            over, worst, longer = 0, np.zeros(3), []
            for k in range(count):
                start, goal, law = random_move(rng, arm, random_law(rng, kind, arm.n_joints), k)
                p = peaks(start, goal, law, timing)
                over += p.over(law)
                worst = np.maximum(worst, (p.velocity, p.acceleration, p.jerk))
                longer.append((p.duration - p.fastest, p.duration / p.fastest - 1.0))
            extra = np.array(longer)
            print(f'{name} {law_name}-{timing.value}: {over} of {count} moves over a limit; '
                  f'worst peak / limit: {_ratios(worst)}; longer than the fastest by median '
                  f'{np.median(extra[:, 0]) * 1e3:.3g} ms ({np.median(extra[:, 1]):.2g}), '
                  f'max {extra[:, 0].max() * 1e3:.3g} ms, relative max '
                  f'{extra[:, 1].max():.2g}', flush=True)
            over_all += over
            total += count
    print(f'{name}: {over_all} of {total} moves over a limit (seed {seed})')


def _ratios(worst: np.ndarray) -> str:
    """Return the worst velocity, acceleration and jerk over their limits, in words."""
    return ', '.join(f'{what} {value:.9f}' for what, value in
                     zip(('velocity', 'acceleration', 'jerk'), worst) if value > 0.0)


def main(argv: list[str]) -> None:
    """Run ``planned`` (ARM N SEED) or ``random_moves`` (random ARM N SEED)."""
    if argv[0] == 'random':
        random_moves(argv[1], int(argv[2]), int(argv[3]))
    else:
        planned(argv[0], int(argv[1]), int(argv[2]))


if __name__ == '__main__':
    main(sys.argv[1:])
