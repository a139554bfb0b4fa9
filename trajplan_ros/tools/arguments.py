# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Command-line argument types and the usage error shared by the ``trajplan`` subcommands."""
from __future__ import annotations

import argparse
import math


__all__ = ['UsageError', 'finite_number', 'positive_count']


class UsageError(Exception):
    """Bad command-line input; the message is the one-line reason."""


def finite_number(text: str) -> float:
    """Parse a finite float, for argparse."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a number: {text!r}') from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f'not a finite number: {text!r}')
    return value


def positive_count(text: str) -> int:
    """Parse an integer of at least 1, for argparse."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not an integer: {text!r}') from None
    if value < 1:
        raise argparse.ArgumentTypeError(f'must be at least 1, got {value}')
    return value
