# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The node's log lines on its busy paths, at a tenth of the cost of rclpy's logger methods.

rclpy's ``logger.info`` finds its caller with ``inspect.getframeinfo`` and ``os.path.realpath``
on every call: about 0.2 ms of interpreter time a line, the larger part of what a topic goal
costs the executor thread (a goal flood logs one or two lines a goal). ``QuickLogger`` hands
the same line to the same rcutils call (console, ``/rosout`` and the log file alike, same
severity, logger name and text), with the caller taken from the frame directly. It takes no
throttle, once or skip-first options; everything else logs through rclpy's logger.
"""
from __future__ import annotations

import sys

from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.impl.rcutils_logger import RcutilsLogger
from rclpy.logging import LoggingSeverity


__all__ = ['QuickLogger']


class QuickLogger:
    """``debug``, ``info``, ``warning`` and ``error`` of a logger, without the caller lookup."""

    def __init__(self, logger: RcutilsLogger) -> None:
        self._logger = logger

    def _log(self, severity: LoggingSeverity, message: str) -> None:
        if not self._logger.is_enabled_for(severity):
            return
        caller = sys._getframe(2)                    # the line that called debug, info, ...
        _rclpy.rclpy_logging_rcutils_log(severity, self._logger.name, message,
                                         caller.f_code.co_name, caller.f_code.co_filename,
                                         caller.f_lineno)

    def debug(self, message: str) -> None:
        self._log(LoggingSeverity.DEBUG, message)

    def info(self, message: str) -> None:
        self._log(LoggingSeverity.INFO, message)

    def warning(self, message: str) -> None:
        self._log(LoggingSeverity.WARN, message)

    def error(self, message: str) -> None:
        self._log(LoggingSeverity.ERROR, message)
