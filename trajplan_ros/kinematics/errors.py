# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The error every arm description raises when it is not a usable chain."""

__all__ = ['InvalidArmModel']


class InvalidArmModel(ValueError):
    """The arm description is not a usable chain (reason in the message)."""
