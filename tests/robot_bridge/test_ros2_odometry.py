"""Integration: the gyro of ``kobuki_sim`` and the ``odometry`` fusion node, each in its own process.

An IMU fault set on the real ``fault_injector`` freezes the gyro the fusion uses; setting the real
ROS 2 parameter ``use_imu`` to false (through the standard service) makes the node take the
encoders' rotation instead. Isolated in a ROS domain of its own; waits by polling.
"""
from __future__ import annotations

import math
import os
import threading

import pytest

pytest.importorskip("rclpy", reason="ROS 2 is an optional extra (pip install 'faultmas[ros2]')")

from robot_bridge.ros2.launch import NodeSpec, Supervisor  # noqa: E402
from robot_bridge.ros2.runtime import RosContext, wait_for  # noqa: E402
from tests.ros_domain import ros_domain  # noqa: E402

DOMAIN = ros_domain(37)


class Listener:
    """The latest message on each topic, and a way to drive the base."""

    def __init__(self, ros: RosContext) -> None:
        import rclpy
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from sensor_msgs.msg import Imu

        self.node = ros.add(rclpy.create_node("odometry_test", namespace="/r", context=ros.context))
        self.latest: dict[str, object] = {}
        self._lock = threading.Lock()
        for topic, kind in (("odom", Odometry), ("odometry/fused", Odometry), ("sensors/imu_data", Imu)):
            self.node.create_subscription(kind, topic, lambda msg, t=topic: self._keep(t, msg), 50)
        self.cmd = self.node.create_publisher(Twist, "commands/velocity_raw", 10)

    def _keep(self, topic: str, msg: object) -> None:
        with self._lock:
            self.latest[topic] = msg

    def yaw(self, topic: str) -> float:
        from robot_bridge.ros2.convert import pose_of
        return pose_of(self.latest[topic])[2]

    def turn(self, seconds: float, rate: float = 0.8) -> None:
        from geometry_msgs.msg import Twist
        stop = threading.Event()
        for _ in range(round(seconds / 0.1)):
            msg = Twist()
            msg.angular.z = rate
            self.cmd.publish(msg)
            stop.wait(0.1)
        self.cmd.publish(Twist())
        stop.wait(1.0)                  # come to rest


@pytest.fixture(scope="module")
def robot():
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    specs = [NodeSpec("r", "kobuki_sim", (("noise", "false"), ("wheelbase_scale", "1.05"))),
             NodeSpec("r", "fault_injector"), NodeSpec("r", "odometry")]
    supervisor = Supervisor(specs, DOMAIN)
    supervisor.start()
    try:
        assert not supervisor.wait_ready(60.0), "the nodes did not come up"
        with RosContext(domain_id=DOMAIN) as ros:
            listener = Listener(ros)
            assert wait_for(lambda: len(listener.latest) == 3, 30), f"topics seen: {list(listener.latest)}"
            yield ros, listener
    finally:
        supervisor.stop()


@pytest.fixture(scope="module")
def parameters(robot):
    from detection.taps.ros2_parameters import Ros2Parameters    # what a rule's set_parameter uses
    setter = Ros2Parameters(domain_id=DOMAIN, timeout=15.0)
    try:
        yield setter
    finally:
        setter.close()


def test_fused_odometry_follows_the_gyro_then_the_encoders_after_use_imu_false(robot, parameters):
    ros, listener = robot
    wheel0, fused0 = listener.yaw("odom"), listener.yaw("odometry/fused")
    listener.turn(1.0)
    wheel_turn = listener.yaw("odom") - wheel0
    fused_turn = listener.yaw("odometry/fused") - fused0
    assert wheel_turn > 0.5
    assert fused_turn == pytest.approx(wheel_turn / 1.05, rel=0.03)     # the gyro: the true rotation

    parameters.set_parameter("/r/fault_injector", "fault", "imu_stuck")
    assert wait_for(lambda: listener.latest["sensors/imu_data"].angular_velocity.z == 0.0, 10)
    fused1 = listener.yaw("odometry/fused")
    listener.turn(1.0)
    assert listener.yaw("odometry/fused") == pytest.approx(fused1, abs=1e-6)     # stuck gyro: no rotation

    parameters.set_parameter("/r/odometry", "use_imu", False)
    wheel2, fused2 = listener.yaw("odom"), listener.yaw("odometry/fused")
    listener.turn(1.0)
    wheel_turn = listener.yaw("odom") - wheel2
    assert wheel_turn > 0.5
    assert listener.yaw("odometry/fused") - fused2 == pytest.approx(wheel_turn, abs=0.01)   # the encoders'


def test_use_imu_refuses_a_non_bool(robot, parameters):
    from diagnosis.actions import ActionError
    with pytest.raises(ActionError, match="refused"):
        parameters.set_parameter("/r/odometry", "use_imu", "maybe")
