# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
A ROS 2 node of this process, spun on a background thread, for talking to the planner node.

One helper for every client of the planner outside the node itself: ``trajplan call``,
``trajplan goal``, ``trajplan demo``, the node benchmark and the integration tests. Its calls
block with timeouts and raise ``TimeoutError`` with the reason, so a script never hangs.
"""
from __future__ import annotations

import os
import queue
import threading
import time
from typing import Any

from geometry_msgs.msg import Point
from nav_msgs.srv import GetPlan
from rcl_interfaces.srv import GetParameters, SetParameters, SetParametersAtomically
import rclpy
from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter, parameter_value_to_python
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from trajplan_ros.tools.node_process import TIMEOUT_S, wait_until

__all__ = ['KEEP_ALL', 'RosClient', 'plan_request']

#: QoS of every service client: reliable and KEEP_ALL, like the node's service. With the
#: services default (KEEP_LAST, depth 10) DDS drops the oldest answers once more than 10 wait
#: in the client's reader before its executor takes them: 20 calls answered together at the
#: node's shutdown can then arrive as 10.
KEEP_ALL = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE)

#: Seconds without an answer after which ``RosClient.call_idempotent`` sends its request again.
RESEND_S = 5.0


def discovery_hint() -> str:
    """Say what to check when no node is found: the node, and the DDS settings both need."""
    domain = os.environ.get('ROS_DOMAIN_ID') or '0 (unset)'
    scope = os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE') or 'SUBNET (unset)'
    return (f'is planner_node running, and with the same ROS_DOMAIN_ID (here {domain}) and '
            f'ROS_AUTOMATIC_DISCOVERY_RANGE (here {scope})? A namespaced node needs the '
            'namespaced name')


def _wait_for_peer(predicate: Any, timeout: float, what: str) -> None:
    """Wait until ``predicate`` holds; else TimeoutError naming ``what`` and what to check."""
    try:
        wait_until(predicate, timeout, what)
    except TimeoutError:
        raise TimeoutError(f'no {what} within {timeout:g} s: {discovery_hint()}') from None


def plan_request(goal: tuple[float, float, float], tolerance: float = 0.0) -> GetPlan.Request:
    """Build a GetPlan request for a tool goal (m, the planner's base frame)."""
    request = GetPlan.Request(tolerance=float(tolerance))
    request.goal.pose.position = Point(x=float(goal[0]), y=float(goal[1]), z=float(goal[2]))
    return request


class RosClient:
    """A node in a context of its own, spun by a SingleThreadedExecutor on a daemon thread."""

    def __init__(self, name: str = 'trajplan_client') -> None:
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(name, context=self.context)
        self._executor = SingleThreadedExecutor(context=self.context)
        self._executor.add_node(self.node)
        self._spinner = threading.Thread(target=self._executor.spin, daemon=True)
        self._spinner.start()
        self._clients: dict[str, Any] = {}
        self._publishers: dict[str, Any] = {}
        self._inboxes: dict[str, tuple[Any, queue.Queue[Any]]] = {}

    def close(self) -> None:
        """Stop spinning and shut the context down."""
        self._executor.shutdown()
        self._spinner.join(timeout=TIMEOUT_S)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)

    def __enter__(self) -> RosClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- services ---------------------------------------------------------------------------

    def client(self, srv_type: Any, name: str, timeout: float = TIMEOUT_S) -> Any:
        """Return a client of service ``name``, once the service is there."""
        if name not in self._clients:
            self._clients[name] = self.node.create_client(srv_type, name,
                                                          qos_profile=KEEP_ALL)
        client = self._clients[name]
        if not client.wait_for_service(timeout_sec=timeout):
            raise TimeoutError(f'no service {name} within {timeout:g} s: {discovery_hint()}')
        return client

    def call_async(self, srv_type: Any, name: str, request: Any,
                   timeout: float = TIMEOUT_S) -> Any:
        """Send ``request`` to service ``name``; return the future of its answer."""
        return self.client(srv_type, name, timeout).call_async(request)

    @staticmethod
    def result(future: Any, timeout: float = TIMEOUT_S) -> Any:
        """Wait for the answer of ``future``."""
        done = threading.Event()
        future.add_done_callback(lambda _: done.set())
        if not done.wait(timeout):
            raise TimeoutError(f'no answer within {timeout:g} s')
        return future.result()

    def call(self, srv_type: Any, name: str, request: Any, timeout: float = TIMEOUT_S) -> Any:
        """Call service ``name`` and wait for its answer."""
        return self.result(self.call_async(srv_type, name, request, timeout), timeout)

    def call_idempotent(self, srv_type: Any, name: str, request: Any,
                        timeout: float = TIMEOUT_S) -> Any:
        """
        Call service ``name`` and wait for its answer, sending the request again while none comes.

        For requests that may be repeated (parameter gets and sets): a new client's first request
        or its answer can be lost while DDS is still matching it with the service, although the
        service is already discovered (ros2/rmw_fastrtps#418 and #842). The request goes again
        every ``RESEND_S`` seconds until ``timeout``.
        """
        deadline = time.monotonic() + timeout
        while True:
            future = self.call_async(srv_type, name, request, timeout)
            wait = min(RESEND_S, deadline - time.monotonic())
            try:
                return self.result(future, max(wait, 0.0))
            except TimeoutError:
                if time.monotonic() >= deadline:
                    raise TimeoutError(f'no answer from {name} within {timeout:g} s') from None

    def get_parameters(self, node: str, names: list[str],
                       timeout: float = TIMEOUT_S) -> list[Any]:
        """Python values of the named parameters of ``node`` (its full name)."""
        answer = self.call_idempotent(GetParameters, f'{node}/get_parameters',
                                      GetParameters.Request(names=names), timeout)
        return [parameter_value_to_python(v) for v in answer.values]

    def set_parameters(self, node: str, params: list[Parameter],
                       atomically: bool = False) -> list[Any]:
        """Set ``params`` on ``node`` (its full name); return the SetParametersResult list."""
        msgs = [p.to_parameter_msg() for p in params]
        if atomically:
            return [self.call_idempotent(
                SetParametersAtomically, f'{node}/set_parameters_atomically',
                SetParametersAtomically.Request(parameters=msgs)).result]
        return self.call_idempotent(SetParameters, f'{node}/set_parameters',
                                    SetParameters.Request(parameters=msgs)).results

    # --- topics -----------------------------------------------------------------------------

    def publisher(self, msg_type: Any, topic: str, timeout: float = TIMEOUT_S,
                  depth: int = 10) -> Any:
        """Return a reliable publisher on ``topic``, once a subscriber has matched it."""
        if topic not in self._publishers:
            self._publishers[topic] = self.node.create_publisher(msg_type, topic, depth)
        pub = self._publishers[topic]
        _wait_for_peer(lambda: pub.get_subscription_count() > 0, timeout,
                       f'subscriber on {topic}')
        return pub

    def publish(self, msg_type: Any, topic: str, *msgs: Any,
                timeout: float = TIMEOUT_S) -> None:
        """Publish ``msgs`` (up to 10) once a subscriber has matched; wait until all have them."""
        pub = self.publisher(msg_type, topic, timeout)
        for msg in msgs:
            pub.publish(msg)
        if not pub.wait_for_all_acked(Duration(seconds=timeout)):
            raise TimeoutError(f'the subscribers on {topic} did not acknowledge within '
                               f'{timeout:g} s')

    def inbox(self, msg_type: Any, topic: str, timeout: float = TIMEOUT_S,
              qos: QoSProfile | int = 10) -> queue.Queue[Any]:
        """Return a queue of the messages arriving on ``topic``, once a publisher matched."""
        if topic not in self._inboxes:
            box: queue.Queue[Any] = queue.Queue()
            sub = self.node.create_subscription(msg_type, topic, box.put, qos)
            self._inboxes[topic] = (sub, box)
        sub, box = self._inboxes[topic]
        _wait_for_peer(lambda: sub.get_publisher_count() > 0, timeout, f'publisher on {topic}')
        return box
