# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The planner node's work queue: every service call in arrival order, plus the newest topic goal.

The executor thread puts work in; the node's one worker thread takes it out. Calls wait in a
bounded queue (``put_call`` refuses one beyond the bound); of the topic goals only the newest
waits, and ``put_goal`` hands back the one it supersedes so the node can log it. ``close``
stops intake and hands back every call still waiting, so that each can be answered. Nothing
here imports rclpy: a call's ``future`` is whatever the node waits on.
"""
from __future__ import annotations

import collections
from dataclasses import dataclass, field
import enum
import math
import threading
import time
from typing import Any, Mapping

from trajplan_ros.search.goal import Goal


__all__ = ['Admission', 'Job', 'Mailbox']


class Admission(enum.Enum):
    """What became of a service call offered to the queue."""

    QUEUED = 'queued'
    FULL = 'full'           # max_queued_calls calls are waiting already
    CLOSED = 'closed'       # the node is shutting down


@dataclass
class Job:
    """One goal for the worker; a service call carries the future its answer goes into."""

    label: str
    goal: Goal                               # in its frame, until the worker poses it
    future: Any = None
    #: a stamped goal's header.stamp (sec, nanosec): its frame is posed then (zero: the newest)
    stamp: tuple[int, int] | None = None
    plan_only: bool = False                  # answered, never sent to the controller
    #: changes to the settings' PlanRequest for this job alone (a MoveIt request's time
    #: budget and scaling; compute_ik's world None when it ignores collisions)
    request_changes: Mapping[str, Any] = field(default_factory=dict)
    start_state: Mapping[str, float] = field(default_factory=dict)   # joint angles it gives
    answer_path: bool = True                 # a call's answer holds the tool path (GetPlan)
    start_must_be_free: bool = False         # refused if the start collides (MoveIt's rule)
    ended: tuple[str, str] = ('', '')        # its first outcome on plan_results: status, reason
    queued_at: float = field(default_factory=time.monotonic)
    answered: bool = False
    planned_answer: bool = False     # the call was answered with a plan
    counted: bool = False            # logged and counted
    reported: bool = False           # its outcome published on plan_results
    taken: threading.Event = field(default_factory=threading.Event)   # the answer is taken

    @property
    def is_call(self) -> bool:
        return self.future is not None

    @property
    def point(self) -> tuple[float, ...]:
        """Return the goal's point, for logs and statuses (NaN for a joint goal not planned)."""
        position = self.goal.position
        return tuple(position.tolist()) if position.size == 3 else (math.nan,) * 3


class Mailbox:
    """Work for the planning thread: every service call in order, plus the newest topic goal."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._calls: collections.deque[Job] = collections.deque()
        self._goal: Job | None = None
        self.closed = False

    def put_call(self, job: Job, limit: int) -> Admission:
        """Queue a service call unless ``limit`` calls are waiting or the queue is closed."""
        with self._cond:
            if self.closed:
                return Admission.CLOSED
            if len(self._calls) >= limit:
                return Admission.FULL
            self._calls.append(job)
            self._cond.notify()
            return Admission.QUEUED

    def put_goal(self, job: Job) -> Job | None:
        """Queue a topic goal; return the waiting goal it supersedes (``job`` itself if closed)."""
        with self._cond:
            if self.closed:
                return job
            superseded, self._goal = self._goal, job
            self._cond.notify()
            return superseded

    def take(self) -> Job | None:
        """Block until there is work (service calls first); None once closed."""
        with self._cond:
            self._cond.wait_for(lambda: self.closed or self._calls or self._goal is not None)
            if self.closed:
                return None
            if self._calls:
                return self._calls.popleft()
            job, self._goal = self._goal, None
            return job

    def wait_for_work(self, timeout: float) -> None:
        """Return when there is work (or the queue is closed), or after ``timeout`` s."""
        with self._cond:
            self._cond.wait_for(lambda: self.closed or self._calls or self._goal is not None,
                                timeout=timeout)

    def waiting(self) -> tuple[int, float]:
        """Return how many calls wait, and how long the oldest has waited (s; 0 if none)."""
        with self._cond:
            oldest = time.monotonic() - self._calls[0].queued_at if self._calls else 0.0
            return len(self._calls), oldest

    def close(self) -> list[Job]:
        """Stop handing out and taking work; return the calls and goal still waiting."""
        with self._cond:
            self.closed = True
            self._cond.notify_all()
            left = list(self._calls) + ([self._goal] if self._goal is not None else [])
            self._calls.clear()
            self._goal = None
            return left
