"""ROS 2 node ``odometry``: wheel odometry fused with the IMU's rotation, switchable by ``use_imu``.

In: ``odom`` (Odometry from the base's encoders) and ``sensors/imu_data`` (Imu; only
``angular_velocity.z`` is used, integrated over the header stamps). Out: ``odometry/fused``
(Odometry), one per wheel-odometry message: the encoders' distance with the gyro's rotation while the
parameter ``use_imu`` is true (default), the encoders' rotation when it is false. ``use_imu`` is a
real ROS 2 parameter: ``-p use_imu:=false`` at start, or the standard ``set_parameters`` service at
run time (what a repair rule's ``set_parameter`` action calls). The fusion itself is
:class:`robot_bridge.sim.odometry_fusion.OdometryFusion`, the embedded simulator's component.

    python -m robot_bridge.ros2.odometry --robot faulty --ros-args -p use_imu:=false
"""
from __future__ import annotations

import math

from robot_bridge.ros2.runtime import require_ros, run_node

require_ros(__name__)

from nav_msgs.msg import Odometry  # noqa: E402
from rcl_interfaces.msg import SetParametersResult  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.node import Node  # noqa: E402
from sensor_msgs.msg import Imu  # noqa: E402

from robot_bridge.ros2.convert import odometry, pose_of  # noqa: E402
from robot_bridge.sim.odometry_fusion import OdometryFusion  # noqa: E402


def _seconds(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


class Increments:
    """Turns the two input streams into the fusion's steps: distance and rotations since the last
    wheel-odometry message (the gyro integrated over its header stamps)."""

    def __init__(self) -> None:
        self._imu_angle = 0.0             # the gyro's rotation integrated since start (rad)
        self._imu_stamp: float | None = None
        self._imu_angle_used = 0.0        # ... up to the last wheel-odometry message
        self._wheel: tuple[float, float, float] | None = None

    def imu(self, msg: Imu) -> None:
        stamp = _seconds(msg.header.stamp)
        if self._imu_stamp is not None and stamp > self._imu_stamp:
            self._imu_angle += msg.angular_velocity.z * (stamp - self._imu_stamp)
        self._imu_stamp = stamp

    def wheel_odometry(self, msg: Odometry) -> tuple[float, float, float] | None:
        """(distance m, wheel rotation rad, gyro rotation rad) since the previous message; None for the first."""
        x, y, yaw = pose_of(msg)
        previous, self._wheel = self._wheel, (x, y, yaw)
        imu_rotation, self._imu_angle_used = self._imu_angle - self._imu_angle_used, self._imu_angle
        if previous is None:
            return None
        wheel_rotation = _wrap(yaw - previous[2])
        mid = previous[2] + wheel_rotation / 2.0
        distance = (x - previous[0]) * math.cos(mid) + (y - previous[1]) * math.sin(mid)
        return distance, wheel_rotation, imu_rotation


class OdometryFusionNode(Node):
    """Keeps one :class:`OdometryFusion` and steps it with each wheel-odometry message."""

    def __init__(self, namespace: str = "", options: object = None, context=None, use_imu: bool = True) -> None:
        super().__init__("odometry", namespace=namespace, context=context)
        self.declare_parameter("use_imu", use_imu)
        self.fusion = OdometryFusion(use_imu=bool(self.get_parameter("use_imu").value))
        self.add_on_set_parameters_callback(self._on_parameters)
        self._increments = Increments()
        self._pub = self.create_publisher(Odometry, "odometry/fused", 50)
        self.create_subscription(Imu, "sensors/imu_data", self._increments.imu, 100)
        self.create_subscription(Odometry, "odom", self._on_wheel_odometry, 100)

    def _on_parameters(self, params) -> SetParametersResult:
        for param in params:
            if param.name == "use_imu":
                if param.type_ != Parameter.Type.BOOL:
                    return SetParametersResult(successful=False, reason="use_imu is a bool (true or false)")
                self.fusion.use_imu = bool(param.value)
                self.get_logger().info(f"use_imu: {self.fusion.use_imu}")
        return SetParametersResult(successful=True)

    def _on_wheel_odometry(self, msg: Odometry) -> None:
        step = self._increments.wheel_odometry(msg)
        if step is None:
            return
        pose = self.fusion.step(*step)
        twist = msg.twist.twist
        self._pub.publish(odometry(pose.x, pose.y, pose.yaw, twist.linear.x, twist.angular.z,
                                   msg.header.stamp))


def main(argv: list[str] | None = None) -> int:
    return run_node(OdometryFusionNode, __doc__.splitlines()[0], argv)


if __name__ == "__main__":
    raise SystemExit(main())
