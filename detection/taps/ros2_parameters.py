"""Setting a ROS 2 node's parameter from a rule (``set_parameter``): ``diagnosis.actions.ParameterSetter``.

Has its own rclpy context and executor thread: a rule fires inside the observers' callback, and
waiting there for a service answer on the same executor would deadlock.
"""
from __future__ import annotations

import threading
from typing import Any

from diagnosis.actions import ActionError


class Ros2Parameters:
    def __init__(self, domain_id: int | None = None, timeout: float = 5.0) -> None:
        from rclpy.node import Node

        from robot_bridge.ros2.runtime import RosContext

        self.timeout = timeout
        self.ros = RosContext(domain_id=domain_id)
        self.node = self.ros.add(Node("faultmas_rule_parameters", context=self.ros.context))
        self.ros.start()
        self._clients: dict[str, object] = {}
        self._lock = threading.Lock()

    def set_parameter(self, node: str, name: str, value: Any) -> None:
        """Set ``name`` of ``node`` (``/laser_driver``) through its ``set_parameters`` service; raise on failure."""
        from rcl_interfaces.srv import SetParameters
        from rclpy.parameter import Parameter

        node = node if node.startswith("/") else "/" + node
        with self._lock:
            client = self._clients.get(node)
            if client is None:
                client = self._clients[node] = self.node.create_client(SetParameters, f"{node}/set_parameters")
        if not client.wait_for_service(timeout_sec=self.timeout):
            raise ActionError(f"set_parameter: node {node} offers no set_parameters service "
                              f"(not running?) within {self.timeout} s")
        try:
            param = Parameter(name, value=value).to_parameter_msg()
        except TypeError as exc:
            raise ActionError(f"set_parameter {node} {name}: {exc}") from None
        done = threading.Event()
        future = client.call_async(SetParameters.Request(parameters=[param]))
        future.add_done_callback(lambda _f: done.set())
        if not done.wait(self.timeout):
            future.cancel()
            raise ActionError(f"set_parameter {node} {name}: no answer within {self.timeout} s")
        result = future.result().results[0]
        if not result.successful:
            raise ActionError(f"set_parameter {node} {name}={value!r} refused: {result.reason or 'no reason given'}")

    def close(self) -> None:
        self.ros.close()
