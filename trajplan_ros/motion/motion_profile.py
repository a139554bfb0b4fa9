# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
How the arm moves to its joint goal: the profile, its timing and each joint's limits.

``MotionProfile`` is the one settings object of the motion (in the spirit of Ruckig's
InputParameter): the library's ``plan(..., profile=)``, the ``trajplan`` command's
``--profile``, ``--timing``, ``--joint-limits``, ``--max-acceleration`` and ``--max-jerk`` and
the node's parameters of the same names all build one.

- ``profile``: ``servo`` (eq. 10, the paper's: each joint starts and stops at once at its
  velocity), ``trapezoidal`` (velocity and acceleration limits) or ``jerk_limited`` (and jerk).
  The planner minimises the profile's duration R = max_i t_i(|dq_i|) (``time_law``).
- ``timing``: ``independent`` (each joint stops at its own t_i, the paper's) or
  ``synchronized`` (every joint arrives at R, its own profile stretched to R by a lower peak
  velocity, as Ruckig's time synchronisation; under ``servo`` a straight line in joint space).

Limits come from where ROS keeps them. Velocity: the URDF's ``<limit velocity>``, capped by the
servo angular velocity (``angular_velocity``). Acceleration and jerk: a
``joint_limits.yaml`` in MoveIt's format (``read_joint_limits``), which also overrides the
URDF's velocity where it sets one; then ``max_acceleration`` / ``max_jerk`` for every joint
without its own. A profile that needs a limit no source gives is refused, naming the joint.
Joints of the file that the arm does not plan (a MoveIt config lists the gripper too) are
ignored; ``ignored_joints`` names them, for a warning.

``velocity_scaling`` and ``acceleration_scaling`` in (0, 1] scale the velocity and the
acceleration limits, as MoveIt's ``max_velocity_scaling_factor`` and
``max_acceleration_scaling_factor`` do; a joint_limits.yaml's ``default_velocity_scaling_factor``
and ``default_acceleration_scaling_factor`` are their defaults (``from_file``; 1 without).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from trajplan_ros.kinematics import ArmModel
from trajplan_ros.motion.time_law import JERK_LIMITED, SERVO, TimeLaw, TRAPEZOIDAL
import yaml

__all__ = ['JointLimits', 'MotionProfile', 'Profile', 'Timing', 'read_joint_limits']

#: The keys of a joint_limits.yaml's default scaling factors, by ``MotionProfile`` field.
SCALING_KEYS = {'velocity_scaling': 'default_velocity_scaling_factor',
                'acceleration_scaling': 'default_acceleration_scaling_factor'}


class Profile(str, Enum):
    """Each joint's velocity profile from rest to rest."""

    SERVO = 'servo'
    TRAPEZOIDAL = 'trapezoidal'
    JERK_LIMITED = 'jerk_limited'


class Timing(str, Enum):
    """When the joints arrive: each at its own time, or all at the motion's end."""

    INDEPENDENT = 'independent'
    SYNCHRONIZED = 'synchronized'


#: The law id of each profile (``time_law``), and the limits it needs beyond velocity.
_KIND = {Profile.SERVO: SERVO, Profile.TRAPEZOIDAL: TRAPEZOIDAL,
         Profile.JERK_LIMITED: JERK_LIMITED}
_NEEDS = {Profile.SERVO: (), Profile.TRAPEZOIDAL: ('acceleration',),
          Profile.JERK_LIMITED: ('acceleration', 'jerk')}
_QUANTITIES = ('velocity', 'acceleration', 'jerk')
_ARTICLE = {'acceleration': 'an', 'jerk': 'a'}


def _positive(value: Any, what: str) -> float:
    """Return ``value`` as a float, or raise ValueError unless it is a finite positive number."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f'{what} must be a number, got {value!r}')
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f'{what} must be finite and positive, got {value!r}')
    return float(value)


@dataclass(frozen=True)
class JointLimits:
    """One joint's limits from a joint_limits.yaml (rad/s, rad/s^2, rad/s^3; None: not set)."""

    velocity: float | None = None
    acceleration: float | None = None
    jerk: float | None = None

    def __post_init__(self) -> None:
        """Refuse a limit that is not a finite positive number (ValueError with the reason)."""
        for name in _QUANTITIES:
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _positive(value, f'{name} limit'))


def _joint_entry(name: str, entry: Any) -> JointLimits:
    """Return one joint's ``JointLimits`` from its MoveIt entry (has_<x>_limits, max_<x>)."""
    if not isinstance(entry, Mapping):
        raise ValueError(f'joint_limits.{name} must be a mapping, got {entry!r}')
    values = {}
    for quantity in _QUANTITIES:
        has = entry.get(f'has_{quantity}_limits', False)
        if not isinstance(has, bool):
            raise ValueError(f'joint_limits.{name}.has_{quantity}_limits must be true or false, '
                             f'got {has!r}')
        if has:
            if f'max_{quantity}' not in entry:
                raise ValueError(f'joint_limits.{name}: has_{quantity}_limits is true but '
                                 f'max_{quantity} is missing')
            values[quantity] = _positive(entry[f'max_{quantity}'],
                                         f'joint_limits.{name}.max_{quantity}')
    return JointLimits(**values)


def read_joint_limits(path: str | Path) -> dict[str, JointLimits]:
    """
    Return each joint's limits from a joint_limits.yaml in MoveIt's format.

    The joints are under a top-level ``joint_limits:`` or under
    ``robot_description_planning: joint_limits:``; each has ``has_<x>_limits`` / ``max_<x>``
    pairs for velocity, acceleration and jerk (integers accepted; a ``max_`` whose ``has_`` is
    false or missing is ignored). Raises ValueError with a one-line reason for a file that
    cannot be read or parsed, or a limit that is not a finite positive number.
    """
    return _read_limits_file(path)[0]


def _read_limits_file(path: str | Path) -> tuple[dict[str, JointLimits], dict[str, float]]:
    """Return a joint_limits.yaml's joints' limits and its default scaling factors (by field)."""
    try:
        data = yaml.safe_load(Path(path).read_text(encoding='utf-8'))
    except OSError as exc:
        raise ValueError(f'cannot read joint limits {path}: {exc.strerror}') from None
    except yaml.YAMLError as exc:
        where = getattr(exc, 'problem_mark', None)
        line = f' at line {where.line + 1}' if where is not None else ''
        problem = getattr(exc, 'problem', None) or 'not YAML'
        raise ValueError(f'cannot parse joint limits {path}{line}: {problem}') from None
    if isinstance(data, Mapping) and 'robot_description_planning' in data:
        data = data['robot_description_planning']
    joints = data.get('joint_limits') if isinstance(data, Mapping) else None
    if not isinstance(joints, Mapping):
        raise ValueError(f'joint limits {path} has no joint_limits: mapping (MoveIt format)')
    scaling = {name: _scaling(data[key], f'{path}: {key}')
               for name, key in SCALING_KEYS.items() if key in data}
    return {str(name): _joint_entry(str(name), entry) for name, entry in joints.items()}, scaling


def _scaling(value: Any, what: str) -> float:
    """Return a scaling factor, or raise ValueError unless it is a number in (0, 1]."""
    factor = _positive(value, what)
    if factor > 1.0:
        raise ValueError(f'{what} must be in (0, 1], got {value!r}')
    return factor


@dataclass(frozen=True)
class MotionProfile:
    """
    The motion's profile, timing and limits (see the module); the default is the paper's.

    :param profile: ``servo``, ``trapezoidal`` or ``jerk_limited``.
    :param timing: ``independent`` or ``synchronized``.
    :param max_acceleration: rad/s^2 for every joint that ``joint_limits`` gives none.
    :param max_jerk: rad/s^3 for every joint that ``joint_limits`` gives none.
    :param joint_limits: joint name -> its limits (``read_joint_limits``).
    :param velocity_scaling: in (0, 1]: every velocity limit (and ``angular_velocity``) times it.
    :param acceleration_scaling: in (0, 1]: every acceleration limit times it.
    """

    profile: Profile | str = Profile.SERVO
    timing: Timing | str = Timing.INDEPENDENT
    max_acceleration: float | None = None
    max_jerk: float | None = None
    joint_limits: Mapping[str, JointLimits] = field(default_factory=dict)
    velocity_scaling: float = 1.0
    acceleration_scaling: float = 1.0

    def __post_init__(self) -> None:
        """Check the settings; raise ValueError with the reason."""
        for name, kind in (('profile', Profile), ('timing', Timing)):
            value = getattr(self, name)
            try:
                object.__setattr__(self, name, kind(value))
            except ValueError:
                choices = ', '.join(k.value for k in kind)
                raise ValueError(f'unknown {name} {value!r}; choose from {choices}') from None
        for name in ('max_acceleration', 'max_jerk'):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _positive(value, name))
        for name in SCALING_KEYS:
            object.__setattr__(self, name, _scaling(getattr(self, name), name))

    @classmethod
    def from_file(cls, joint_limits: str | Path | None, **settings: Any) -> MotionProfile:
        """
        Return the profile with ``settings`` and the limits of a joint_limits.yaml (or none).

        A scaling factor that ``settings`` leaves out (or gives as None) is the file's default.
        """
        limits, scaling = _read_limits_file(joint_limits) if joint_limits else ({}, {})
        given = {k: v for k, v in settings.items() if v is not None or k not in SCALING_KEYS}
        return cls(joint_limits=limits, **{**scaling, **given})

    def ignored_joints(self, arm: ArmModel) -> list[str]:
        """Return the joints of ``joint_limits`` that the arm does not have (they are ignored)."""
        return sorted(set(self.joint_limits) - set(arm.joint_names))

    def time_law(self, arm: ArmModel, omega: float) -> TimeLaw:
        """
        Return every joint's time law on ``arm`` at servo angular velocity ``omega`` (rad/s).

        The scaling factors apply to the velocity and acceleration limits. Raises ValueError
        naming the joint when the profile needs a limit that no source gives.
        """
        own = [self.joint_limits.get(name, JointLimits()) for name in arm.joint_names]
        urdf = np.asarray(arm.velocity, dtype=float)
        velocity = self.velocity_scaling * np.minimum(
            float(omega), [v.velocity or u for v, u in zip(own, urdf)])
        settings = {'acceleration': self.max_acceleration, 'jerk': self.max_jerk}
        limits = {'acceleration': np.full(len(own), np.inf), 'jerk': np.full(len(own), np.inf)}
        for quantity in _NEEDS[self.profile]:
            values = [getattr(v, quantity) or settings[quantity] for v in own]
            missing = [name for name, value in zip(arm.joint_names, values) if value is None]
            if missing:
                raise ValueError(
                    f'the {self.profile.value} profile needs {_ARTICLE[quantity]} {quantity} '
                    f'limit for joint {missing[0]}: none in the joint limits and no '
                    f'max_{quantity} given')
            limits[quantity] = np.array(values, dtype=float)
        limits['acceleration'] = self.acceleration_scaling * limits['acceleration']
        return TimeLaw(_KIND[self.profile], velocity, limits['acceleration'], limits['jerk'])

    def describe(self) -> str:
        """Return the profile and timing in a few words, e.g. ``trapezoidal, synchronized``."""
        scaled = [f'{name.split("_")[0]} x{value:g}' for name in SCALING_KEYS
                  if (value := getattr(self, name)) != 1.0]
        return ', '.join([self.profile.value, self.timing.value] + scaled)
