# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The one error of the collision package: input refused with a one-line reason."""

__all__ = ['InvalidCollisionInput']


class InvalidCollisionInput(ValueError):
    """A collision geometry, mesh, SRDF or scene that is refused (the reason in the message)."""
