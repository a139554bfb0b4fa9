# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The planner node's work queue: every service call in order, plus the newest topic goal.

The executor threads put work in; the node's one worker thread takes it out. A service call's
callback waits on the job's ``done`` event for its answer.
"""
from __future__ import annotations

import collections
from dataclasses import dataclass
import threading

from nav_msgs.msg import Path


__all__ = ['Job', 'Mailbox']


@dataclass
class Job:
    """
    One goal for the worker.

    For a service call, ``done`` is set once ``path`` is final and ``answered`` once the
    service callback has taken it.
    """

    label: str
    goal: tuple[float, float, float]
    tolerance: float | None = None
    done: threading.Event | None = None
    answered: threading.Event | None = None
    path: Path | None = None


class Mailbox:
    """Work for the planning thread: every service call in order, plus the newest topic goal."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._calls: collections.deque[Job] = collections.deque()
        self._goal: Job | None = None
        self._current: Job | None = None
        self.closed = False

    def put_call(self, job: Job) -> bool:
        """Queue a service call; False once closed (it will not be planned)."""
        with self._cond:
            if self.closed:
                return False
            self._calls.append(job)
            self._cond.notify()
            return True

    def put_goal(self, job: Job) -> Job | None:
        """Queue a topic goal; return the waiting goal it replaces, if any."""
        with self._cond:
            dropped, self._goal = self._goal, job
            self._cond.notify()
            return dropped

    def wait_for_work(self, timeout: float) -> None:
        """Return when there is work (or the mailbox is closed), or after ``timeout`` seconds."""
        with self._cond:
            self._cond.wait_for(lambda: self.closed or self._calls or self._goal is not None,
                                timeout=timeout)

    def take(self) -> Job | None:
        """Block until there is work (service calls first); None once closed."""
        with self._cond:
            self._current = None
            while not self.closed and not self._calls and self._goal is None:
                self._cond.wait()
            if self.closed:
                return None
            if self._calls:
                self._current = self._calls.popleft()
            else:
                self._current, self._goal = self._goal, None
            return self._current

    def close(self) -> list[Job]:
        """Stop handing out work; return the service calls still waiting for an answer."""
        with self._cond:
            self.closed = True
            self._cond.notify_all()
            waiting = [j for j in (self._current, *self._calls) if j is not None and j.done]
            self._calls.clear()
            return waiting
