# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Frames of stamped inputs: the arm's URDF links, and any other frame through tf2.

``listen`` gives the node a tf2 Buffer fed by a TransformListener (``/tf``, ``/tf_static``), or
None where ``tf2_ros`` does not import (it has no PyPI wheel). ``frame_pose`` poses a frame in
the base frame: through tf where tf knows it or where the URDF does not have it, at a stamp
(zero: the latest) and waiting up to a timeout for it; else by the robot's own forward
kinematics. Goals wait (the worker thread asks; the executor, which feeds the buffer, never
blocks); obstacles do not: they take the newest transform when they arrive.
"""
from __future__ import annotations

import time
from typing import Any, Callable, Iterable, Mapping

import numpy as np
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.time import Time
from trajplan_ros.kinematics.rotations import rotation_matrix, unit_quaternion
from trajplan_ros.ros.settings import Settings

__all__ = ['HOW_TO', 'Transforms', 'arrival_note', 'frame_pose', 'frame_problem', 'listen']

#: How long a goal's wait for its frame goes on before it asks whether to stop, s.
WAIT_SLICE = 0.1
#: How to get tf2's Python side on each route.
HOW_TO = ('with ROS from apt: sudo apt install ros-jazzy-tf2-ros-py; with the PyPI wheels: '
          'build ../shared/tf2 with ../shared/ros_interfaces/build_ros_interfaces.sh and put '
          'the printed PYTHONPATH and LD_LIBRARY_PATH in the environment')


class Transforms:
    """A tf2 buffer on the node, and the poses of frames in it."""

    def __init__(self, node: Node, tf2_ros: Any) -> None:
        self._tf2 = tf2_ros
        self.buffer = tf2_ros.Buffer()        # no node: given one, it adds a tf2_frames service
        self._listener = tf2_ros.TransformListener(self.buffer, node, spin_thread=False)

    def knows(self, target: str, frame: str) -> bool:
        """Return whether tf can pose ``frame`` in ``target`` now (its latest transform)."""
        return self.buffer.can_transform(target, frame, Time())

    def pose(self, target: str, frame: str, stamp: tuple[int, int], timeout: float,
             stop: Callable[[], bool] | None = None) -> np.ndarray:
        """
        Return the 4x4 pose of ``frame`` in ``target`` at ``stamp`` (sec, nanosec).

        A stamp of zero takes the latest transform. Waits up to ``timeout`` s for it to come,
        in slices of ``WAIT_SLICE`` after which ``stop()`` True ends the wait; ValueError with
        the frame and tf2's error when it does not come.
        """
        when = Time(seconds=stamp[0], nanoseconds=stamp[1]) if any(stamp) else Time()
        deadline = time.monotonic() + timeout
        while not (stop is not None and stop()):
            left = min(deadline - time.monotonic(), WAIT_SLICE)
            if (self.buffer.can_transform(target, frame, when, Duration(seconds=max(left, 0.0)))
                    or left <= 0.0):
                break
        try:
            found = self.buffer.lookup_transform(target, frame, when)
        except self._tf2.TransformException as exc:
            at = 'the latest' if not any(stamp) else f'stamp {stamp[0]}.{stamp[1]:09d}'
            raise ValueError(f"frame '{frame}' has no transform to '{target}' at {at} within "
                             f'{timeout:g} s: {type(exc).__name__}: '
                             f"{str(exc).splitlines()[0] if str(exc) else ''}") from None
        t, q = found.transform.translation, found.transform.rotation
        pose = np.eye(4)
        pose[:3, :3] = rotation_matrix(unit_quaternion((q.x, q.y, q.z, q.w)))   # ValueError
        pose[:3, 3] = t.x, t.y, t.z
        return pose


def listen(node: Node) -> Transforms | None:
    """Return the node's tf2 buffer and listener; None where tf2_ros does not load (logged)."""
    try:
        import tf2_ros
    except Exception:  # noqa: BLE001 - not installed, or its C libraries do not load
        node.get_logger().info(f"frames outside the arm's URDF need tf2, which does not load "
                               f'here: {HOW_TO}')
        return None
    return Transforms(node, tf2_ros)


def frame_pose(frame: str, settings: Settings, angles: Mapping[str, float],
               transforms: Transforms | None, stamp: tuple[int, int] = (0, 0),
               wait: float = 0.0, stop: Callable[[], bool] | None = None) -> np.ndarray:
    """
    Return the 4x4 pose of ``frame`` in the base frame (ValueError: why it cannot be had).

    tf's, where tf knows the frame now or the URDF does not have it (at ``stamp``, waiting up
    to ``wait`` s unless ``stop()``); else, and where tf has no transform of a URDF link at
    that stamp, the URDF's forward kinematics at joint ``angles``. '' is the base.
    """
    base = settings.base_frame
    if not frame or frame == base:
        return np.eye(4)
    in_urdf = frame in settings.frames.links
    if transforms is not None and (not in_urdf or transforms.knows(base, frame)):
        try:
            return transforms.pose(base, frame, stamp, wait, stop)
        except ValueError:
            if not in_urdf:
                raise                              # a URDF link: the robot's own FK instead
    problem = frame_problem(frame, settings, transforms is not None)
    if problem:
        raise ValueError(problem)
    return settings.frames.to_base(frame, angles)


def frame_problem(frame: str, settings: Settings, with_tf: bool) -> str | None:
    """
    Return why ``frame`` can never be posed, or None.

    ``with_tf``: any frame may come through tf (``frame_pose`` then waits for it); without tf,
    only the URDF's links are known.
    """
    if not frame or frame == settings.base_frame or with_tf:
        return None
    if frame in settings.frames.links:
        return None
    return (f"frame '{frame}' is not a link of the robot; known frames: "
            f"{', '.join(settings.frames.links)} (other frames need tf2)")


def arrival_note(frames: Iterable[str], settings: Settings) -> str:
    """Say the frames obstacles came in, posed as they were on arrival ('' for the base only)."""
    others = sorted({f for f in frames if f and f != settings.base_frame})
    if not others:
        return ''
    return f"; posed as {', '.join(repr(f) for f in others)} stood on arrival, and kept there"
