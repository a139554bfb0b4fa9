# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The search for the fastest joint goal whose direct motion is free.

It is the direct method's own: the goal has a whole set of joint solutions, and among them it
takes the fastest whose motion keeps clear (``collision.free_motion.check_motion``). It checks
the optimiser's answer first; when that collides it projects random joint vectors onto the
goal's solutions, polishes copies of them to local minima of the motion time, checks them
fastest first, in rounds, and moves the best free one towards faster colliding ones by
bisection along the solutions.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trajplan_ros.collision.distances import CollisionWorld
from trajplan_ros.collision.free_motion import check_motion, Clearance, StartLimits
from trajplan_ros.motion.motion_profile import Timing
from trajplan_ros.motion.time_law import TimeLaw
from trajplan_ros.search.objective import Objective
from trajplan_ros.search.polish import Linearisation, polish

__all__ = ['distinct_goals', 'free_joint_goal', 'project_onto_goal', 'reached_goals',
           'SearchOutcome']

#: Random joint vectors the search projects onto the goal's solutions in one round (a goal's
#: free solutions can be few, and a redundant arm's solutions many).
SAMPLES = 192
#: Newton steps of that projection.
PROJECTION_STEPS = 12
#: Bisection steps from the best free candidate towards a faster colliding one.
BISECTIONS = 6
#: A bisection step is checked only where it would shorten the best motion by this share.
GAIN = 2e-3
#: Candidate joint goals closer than this in every joint (rad) are one.
SAME_GOAL = 1e-4


@dataclass(frozen=True)
class SearchOutcome:
    """The search's choice: planned joint angles x (None: no free motion found) and why."""

    x: np.ndarray | None
    clearance: Clearance          # the chosen motion's, or the blocked first candidate's
    checked: int                  # motions checked
    goals: np.ndarray             # the first round's reached joint goals, fastest first (K, m)


def project_onto_goal(obj: Objective, x: np.ndarray, steps: int = PROJECTION_STEPS) -> np.ndarray:
    """Return joint vectors x (K, m) after Newton steps onto the goal's solutions."""
    for _ in range(steps):
        here = Linearisation.at(obj, x, 1.0, newton_only=True)
        x = np.clip(x + here.newton(here.c), obj.lower, obj.upper)
    return x


def reached_goals(obj: Objective, rng: np.random.Generator, tolerance: float) -> np.ndarray:
    """
    Return reached joint goals, fastest first: random ones projected, and those polished.

    Polished copies often end at one local minimum: of goals within ``SAME_GOAL`` (rad) of each
    other in every joint only the fastest is kept (their motions are the same to the check).
    """
    drawn = rng.uniform(obj.lower, obj.upper, (SAMPLES, obj.arm.planned))
    projected = project_onto_goal(obj, drawn)
    x = np.vstack((projected, polish(obj, projected)))
    x = x[obj.errors(obj.tool(x)) <= tolerance]
    return distinct_goals(x[np.argsort(obj.motion_time(x), kind='stable')])


def distinct_goals(x: np.ndarray) -> np.ndarray:
    """Return the rows of x (fastest first) without those within ``SAME_GOAL`` of a faster."""
    _, first = np.unique(np.round(x / SAME_GOAL), axis=0, return_index=True)
    return x[np.sort(first)]


def free_joint_goal(obj: Objective, world: CollisionWorld, law: TimeLaw, timing: Timing,
                    x0: np.ndarray, rng: np.random.Generator, tolerance: float
                    ) -> SearchOutcome:
    """
    Return the fastest joint goal found whose motion from the start is free (see the module).

    ``x0``: the optimiser's answer (planned joints), checked first; ``law``: the whole arm's
    time law; ``tolerance``: the largest error (m) of a reached goal.
    """
    limits = StartLimits.at(world, obj.start)

    def check(x: np.ndarray) -> Clearance:
        return check_motion(world, obj.start, obj.full(x)[0], law, timing, True, limits)

    first = check(x0)
    if first.free:
        return SearchOutcome(x0, first, 1, np.empty((0, obj.arm.planned)))
    checked, colliding, best, drawn = 1, [x0], None, []
    for _ in range(_rounds(obj)):
        drawn.append(reached_goals(obj, rng, tolerance))
        found, spent = _first_free(obj, check, drawn[-1], best, colliding)
        checked += spent
        if found is None and best is not None:
            break
        best = found or best
    if best is None:
        return SearchOutcome(None, first, checked, drawn[0])
    colliding.sort(key=lambda x: _time(obj, x))
    for target in colliding[:3]:
        best, spent = _bisect(obj, check, best, target, tolerance)
        checked += spent
    return SearchOutcome(best[0], best[1], checked, drawn[0])


def _rounds(obj: Objective) -> int:
    """
    Return the most rounds of candidates: one per free direction of the solutions past two.

    ``SAMPLES`` vectors cover a solution set of two dimensions (a 5-joint arm's positions);
    each further dimension gets a round more. A round follows only while the last one found a
    faster free motion, or none has been found yet.
    """
    return max(1, obj.null_directions - 1)


def _first_free(obj: Objective, check, candidates: np.ndarray,
                best: tuple[np.ndarray, Clearance] | None, colliding: list[np.ndarray]
                ) -> tuple[tuple[np.ndarray, Clearance] | None, int]:
    """
    Return the first free motion among candidates (fastest first) faster than ``best``.

    Only candidates that would shorten ``best`` by ``GAIN`` are checked; the colliding ones
    are added to ``colliding``. Also returns the motions checked.
    """
    if best is not None:
        candidates = candidates[obj.motion_time(candidates) < (1.0 - GAIN) * _time(obj, best[0])]
    for n, x in enumerate(candidates):
        clearance = check(x)
        if clearance.free:
            return (x, clearance), n + 1
        colliding.append(x)
    return None, len(candidates)


def _time(obj: Objective, x: np.ndarray) -> float:
    """Return the motion time to joint goal x (planned joints)."""
    return float(obj.motion_time(x[None])[0])


def _bisect(obj: Objective, check, free: tuple[np.ndarray, Clearance], blocked: np.ndarray,
            tolerance: float) -> tuple[tuple[np.ndarray, Clearance], int]:
    """
    Return the fastest free point found between ``free`` and ``blocked`` on the solutions.

    Each step takes the (projected) middle of what is left: checked, it moves the search
    towards ``blocked`` where free and away where not; a middle that would not shorten the best
    motion by ``GAIN`` is not checked (the search moves on towards ``blocked``). The search
    ends once the nearest blocked point is no faster than that. Also returns the motions
    checked.
    """
    low, high, best, spent = 0.0, 1.0, free, 0
    best_time, high_time = _time(obj, free[0]), _time(obj, blocked)
    for _ in range(BISECTIONS):
        if high_time > (1.0 - GAIN) * best_time:
            break
        middle = 0.5 * (low + high)
        x = project_onto_goal(obj, ((1.0 - middle) * free[0] + middle * blocked)[None])[0]
        if _time(obj, x) > (1.0 - GAIN) * best_time:
            low = middle
            continue
        clearance = check(x) if obj.errors(obj.tool(x[None]))[0] <= tolerance else None
        spent += clearance is not None
        if clearance is not None and clearance.free:
            low = middle
            best, best_time = (x, clearance), _time(obj, x)
        else:
            high, high_time = middle, _time(obj, x)
    return best, spent
