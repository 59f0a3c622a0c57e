"""Set a parameter of another ROS 2 node through its standard ``set_parameters`` service.

This is the ROS 2 end of a repair rule's ``set_parameter`` action
(:class:`diagnosis.actions.ParameterSetter`): ``RosParameterSetter(node).set_parameter("/faulty/odometry",
"use_imu", False)``. It blocks until the node answered (or ``timeout``), so it must not run on the
thread that spins ``node``'s executor. A node that does not answer, or refuses the value, raises
``ParameterError`` with the node's reason.
"""
from __future__ import annotations

from typing import Any


class ParameterError(RuntimeError):
    """The parameter could not be set: no such node, no answer in time, or the node refused it."""


class RosParameterSetter:
    """Sets parameters of remote nodes from ``node`` (one parameter client per remote node, kept)."""

    def __init__(self, node: Any, namespace: str = "", timeout: float = 5.0) -> None:
        self.node, self.namespace, self.timeout = node, namespace.rstrip("/"), timeout
        self._clients: dict[str, Any] = {}

    def _full_name(self, node_name: str) -> str:
        return node_name if node_name.startswith("/") else f"{self.namespace}/{node_name}"

    def set_parameter(self, node: str, name: str, value: Any) -> None:
        from rclpy.parameter import Parameter
        from rclpy.parameter_client import AsyncParameterClient

        target = self._full_name(node)
        client = self._clients.get(target)
        if client is None:
            client = self._clients[target] = AsyncParameterClient(self.node, target)
        if not client.wait_for_services(timeout_sec=self.timeout):
            raise ParameterError(f"node {target} offers no set_parameters service within {self.timeout:g} s")
        future = client.set_parameters([Parameter(name, value=value)])
        done = _wait(future, self.timeout)
        if not done:
            raise ParameterError(f"node {target} did not answer set_parameters({name}) within {self.timeout:g} s")
        result = future.result().results[0]
        if not result.successful:
            raise ParameterError(f"node {target} refused {name}={value!r}: {result.reason or 'no reason given'}")


def _wait(future: Any, timeout: float) -> bool:
    import threading
    event = threading.Event()
    future.add_done_callback(lambda _: event.set())
    return event.wait(timeout) or future.done()
