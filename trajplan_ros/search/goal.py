# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
``Goal``: what a plan must reach, as one object: its kind, its target, its tolerances, its frame.

The kinds (``Goal.kind``): a tool point ("free"); a point with the tool axis along the goal ray
("radial", eq. 12-13); a point with the tool axis along a direction ("approach"); a point and
the tool frame's whole orientation ("pose"); every joint's angle ("joints"). Tolerances larger
than ``EXACT`` make a region of it: the plan is then the fastest motion into the region
(``search.region``). The node's topics and services, move_group's constraints, the ``trajplan``
command and its CSV lines each build one ``Goal``; the planner and the objective read it.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from enum import Enum
from types import MappingProxyType
from typing import Any, Mapping, Sequence

import numpy as np

from trajplan_ros.kinematics.rotations import quaternions, rotation_matrix, unit_quaternion

__all__ = ['DEFAULT_AXIS_TOLERANCE', 'DEFAULT_ORIENTATION_TOLERANCE', 'DEFAULT_TOLERANCE',
           'EXACT', 'Goal', 'InvalidRequest', 'Mode', 'TOP_DOWN', 'unit_direction']


class Mode(str, Enum):
    """Which constraints a plan to a point must meet besides the position."""

    FREE = 'free'
    RADIAL = 'radial'
    APPROACH = 'approach'
    POSE = 'pose'


class InvalidRequest(ValueError):
    """A goal or start that is refused before any optimisation (reason in the message)."""


#: The approach direction of a grasp from above (base frame).
TOP_DOWN = (0.0, 0.0, -1.0)
#: Largest error (m) that counts as reached unless the caller says otherwise.
DEFAULT_TOLERANCE = 1e-6
#: Largest angle (rad) between the tool axis and its target that counts as met, by mode: the
#: goal ray of the paper's radial mode is met exactly; an approach direction within 1 mrad,
#: as a small arm's URDF axes, off by micro-radians, often cannot point exactly along it.
DEFAULT_AXIS_TOLERANCE = MappingProxyType({Mode.RADIAL.value: 1e-6, Mode.APPROACH.value: 1e-3})
#: Largest angle (rad) of the rotation between a pose's goal orientation and the reached one
#: that counts as met: a six- or seven-joint arm meets a pose exactly.
DEFAULT_ORIENTATION_TOLERANCE = 1e-6
#: A tolerance of at most this (m or rad) is the goal itself: a region that small could gain
#: some 1e-6 of the motion time.
EXACT = 1e-6


def unit_direction(direction: np.ndarray | Sequence[float]) -> np.ndarray:
    """Return an approach direction as a unit vector; InvalidRequest if it has none."""
    d = np.array(direction, dtype=float).ravel()
    if d.shape != (3,) or not np.all(np.isfinite(d)) or not np.any(d):
        raise InvalidRequest(f'approach must be 3 finite numbers, not all zero, got {d.tolist()}')
    return d / np.linalg.norm(d)


@dataclass(frozen=True)
class Goal:
    """
    One goal: where the tool must go (or the joints), how closely, and in which frame.

    :param position: the tool point (x, y, z), m, in ``frame``; empty for a joint goal (and
        in the node's settings, which hold a goal's kind and tolerances before its point).
    :param mode: "free" (position only), "radial" (eq. 12-13: the tool axis along the goal
        ray, pointing outward, too), "approach" (the tool axis along ``approach``) or "pose"
        (the tool frame's whole orientation is ``orientation``).
    :param approach: approach mode: the direction the tool axis points along, in the base
        frame (need not be a unit vector); the default (0, 0, -1) is a grasp from above.
    :param orientation: pose mode: the tool (tip) frame's orientation in ``frame``, a unit
        quaternion (x, y, z, w). Approach mode: given, the tool axis points along its z axis
        instead of ``approach`` (a pose whose rotation about z is free).
    :param joint_goal: a joint goal instead of a point: every joint's angle (rad), the planned
        ones (the others keep their start), or angles by joint name (the others keep their
        start, within the limits). ``position`` and the mode's settings are then not read.
    :param tolerance: largest position error (m); above ``EXACT`` the goal is a ball.
    :param axis_tolerance: radial and approach modes: largest angle (rad) of the tool axis to
        the goal ray or the approach direction; None: the mode's ``DEFAULT_AXIS_TOLERANCE``.
    :param orientation_tolerance: pose mode: largest angle (rad) of the rotation between the
        goal orientation and the reached one.
    :param frame: the frame ``position`` and ``orientation`` are in; '' is the arm's base
        frame. The planner takes goals in the base frame (``moved`` brings one there).
    """

    position: Sequence[float] = ()
    mode: Mode | str = Mode.FREE
    approach: Sequence[float] = TOP_DOWN
    orientation: Sequence[float] | None = None
    joint_goal: Sequence[float] | Mapping[str, float] | None = None
    tolerance: float = DEFAULT_TOLERANCE
    axis_tolerance: float | None = None
    orientation_tolerance: float = DEFAULT_ORIENTATION_TOLERANCE
    frame: str = ''

    def __post_init__(self) -> None:
        """Hold the numbers as floats (ValueError if they are not numbers), the mode as a Mode."""
        set_ = object.__setattr__
        set_(self, 'position', np.asarray(self.position, dtype=float).ravel())
        if self.mode not in tuple(Mode) + tuple(m.value for m in Mode):
            raise ValueError(f"mode must be one of {', '.join(m.value for m in Mode)}, "
                             f'got {self.mode!r}')
        set_(self, 'mode', Mode(self.mode))
        set_(self, 'approach', tuple(float(v) for v in np.ravel(self.approach)))
        if self.orientation is not None:
            set_(self, 'orientation', tuple(float(v) for v in np.ravel(self.orientation)))
        if isinstance(self.joint_goal, Mapping):
            set_(self, 'joint_goal', MappingProxyType(
                {str(k): float(v) for k, v in self.joint_goal.items()}))
        elif self.joint_goal is not None:
            set_(self, 'joint_goal', np.asarray(self.joint_goal, dtype=float).ravel())

    @property
    def kind(self) -> str:
        """Return the goal's kind: "joints", or the mode's name."""
        return 'joints' if self.joint_goal is not None else self.mode.value

    @property
    def approach_direction(self) -> np.ndarray:
        """Return approach mode's unit direction: the orientation's z axis, else ``approach``."""
        if self.orientation is None:
            return unit_direction(self.approach)
        try:
            return rotation_matrix(unit_quaternion(self.orientation))[:, 2]
        except ValueError as exc:
            raise InvalidRequest(str(exc)) from None

    @property
    def axis_limit(self) -> float:
        """Return the axis tolerance in force: ``axis_tolerance``, or the mode's default."""
        if self.axis_tolerance is not None:
            return self.axis_tolerance
        return DEFAULT_AXIS_TOLERANCE.get(self.mode.value, DEFAULT_AXIS_TOLERANCE['radial'])

    @property
    def angle_limit(self) -> float:
        """Return the largest angle error that counts as met: the pose's, or ``axis_limit``."""
        return self.orientation_tolerance if self.mode is Mode.POSE else self.axis_limit

    def replace(self, **changes: Any) -> Goal:
        """Return a copy with ``changes`` (as ``dataclasses.replace``)."""
        return replace(self, **changes)

    def moved(self, pose: np.ndarray) -> Goal:
        """
        Return this goal in the base frame, ``pose`` (4x4) being its frame's pose there.

        The position and orientation turn and move with the frame; the approach direction
        and a joint goal do not depend on it.
        """
        rotation, shift = pose[:3, :3], pose[:3, 3]
        position = rotation @ self.position + shift if self.position.size else self.position
        orientation = None if self.orientation is None else quaternions(
            (rotation @ rotation_matrix(unit_quaternion(self.orientation)))[None])[0]
        return replace(self, position=position, orientation=orientation, frame='')

    def validate(self) -> None:
        """Raise ValueError with a one-line reason when a setting is not a goal's."""
        positive = {'tolerance': self.tolerance, 'axis_tolerance': self.axis_limit,
                    'orientation_tolerance': self.orientation_tolerance}
        for name, value in positive.items():
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
                raise ValueError(f'{name} must be finite and positive, got {value!r}')
        unit_direction(self.approach)
        if self.orientation is not None and self.mode not in (Mode.POSE, Mode.APPROACH):
            raise ValueError(f'an orientation is for pose and approach modes, not '
                             f'{self.mode.value}')
        if not isinstance(self.frame, str):
            raise ValueError(f'frame must be a frame name, got {self.frame!r}')
