# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The ``trajplan bench`` subcommand, in modules by concept.

``methods`` (the rows of the table), ``cases`` (the goals), ``runner`` (every method on every
goal), ``report`` (tables and CSV files) and ``command`` (the command line).
"""
from trajplan_ros.tools.bench.command import add_parser

__all__ = ['add_parser']
