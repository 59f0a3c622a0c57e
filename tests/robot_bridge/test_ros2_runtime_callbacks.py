"""A callback that raises costs its tick, not the context's executor thread (before: one exception in one
callback ended ``RosContext``'s spin thread, and every node of the context went deaf and mute)."""
from __future__ import annotations

import logging

import pytest

pytest.importorskip("rclpy", reason="ROS 2 is an optional extra (pip install 'faultmas[ros2]')")

from robot_bridge.ros2.runtime import RosContext, wait_for  # noqa: E402
from tests.ros_domain import ros_domain  # noqa: E402

DOMAIN = ros_domain(44)      # not the other ROS test modules' domains


def test_a_timer_callback_that_raises_does_not_stop_the_executor(caplog):
    import rclpy.node

    calls = []

    def tick():
        calls.append(1)
        if len(calls) <= 3:
            raise ValueError("a bad message")

    with caplog.at_level(logging.WARNING, logger="robot_bridge.ros2.runtime"):
        with RosContext(domain_id=DOMAIN) as ros:
            node = ros.add(rclpy.node.Node("raising_timer", context=ros.context))
            node.create_timer(0.02, tick)
            assert wait_for(lambda: len(calls) >= 10, 30), f"{len(calls)} ticks: the executor stopped"
            assert ros._thread.is_alive()
    errors = [r for r in caplog.records if "rclpy executor: a callback failed" in r.getMessage()]
    assert len(errors) == 1 and "ValueError('a bad message')" in errors[0].getMessage()   # once, not per tick
