"""The recorder starts only on a settled graph with every node of the plan; one it cannot see fails the
run with the node's name (a fixed wait once recorded runs without components, silently)."""
from __future__ import annotations


import pytest

from detection.learned.scenario import settled_graph
from tests.ros_domain import ros_domain  # noqa: E402

DOMAIN = ros_domain(71)


def test_the_graph_is_taken_once_every_planned_node_is_there_and_a_missing_one_is_named():
    import rclpy
    from std_msgs.msg import String

    from robot_bridge.ros2.runtime import RosContext

    with RosContext(domain_id=DOMAIN) as ros:
        talker = ros.add(rclpy.create_node("talker", namespace="/faulty", context=ros.context))
        talker.create_publisher(String, "/faulty/chatter", 10)
        probe = ros.add(rclpy.create_node("probe", context=ros.context))
        components, topics = settled_graph(probe, {"faulty_talker"}, "run 1", timeout_s=30.0)
        assert components["faulty_talker"].outputs == ["/faulty/chatter"]
        assert topics == {"/faulty/chatter": "std_msgs/msg/String"}
        with pytest.raises(RuntimeError, match=r"run 2: the ROS 2 graph did not settle in 3 s \(nodes not seen: helper_ghost\)"):
            settled_graph(probe, {"faulty_talker", "helper_ghost"}, "run 2", timeout_s=3.0)
