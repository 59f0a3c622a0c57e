"""ROS 2 node ``kobuki_sim``: the simulator's Kobuki physics behind kobuki_ros's topics.

In: ``commands/velocity`` (Twist; the base stops 0.6 s after the last one) and, latched,
``faults/active`` from ``fault_injector`` (the sensor and mechanical part of a fault: frozen
encoders, stuck wheels, a faulty gyro) and ``commands/reset_odometry`` (Empty). Out, at ``rate`` Hz:
``odom`` (Odometry integrated from the encoder ticks by :mod:`robot_bridge.sim.odometry`, as the real
base does, so an encoder fault freezes it), ``sensors/imu_data`` (Imu: the gyro's yaw rate of
:mod:`robot_bridge.sim.imu` with IMU faults applied, and the heading integrated from it, as
kobuki_ros publishes), ``sensors/core`` (kobuki_msgs SensorState is not a wheel: its encoder fields
as JSON in a String), ``joint_states`` and ``ground_truth`` (the true pose in frame ``world``, which
a real robot does not have).

Parameters besides the pose and ``seed``: ``left_radius_scale``, ``right_radius_scale``,
``wheelbase_scale`` (systematic wheel-odometry error, see ``kobuki.BaseParams``; 1.0 = exact) and
``gyro_bias`` (rad/s), ``gyro_scale`` (relative): the gyro's calibration residuals.

The physics is :func:`robot_bridge.sim.kobuki.step`, the same step function as the embedded
simulator; a fixed ``1/rate`` s per timer tick keeps runs reproducible for a given ``seed``, and the
header stamps count that physics time (from the node's start), as a real base's stamps count real time.
"""
from __future__ import annotations

import json
import math

from robot_bridge.ros2.runtime import require_ros, run_node

require_ros(__name__)

import numpy as np  # noqa: E402
from geometry_msgs.msg import Twist  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.time import Time  # noqa: E402
from sensor_msgs.msg import Imu, JointState  # noqa: E402
from std_msgs.msg import Empty, String  # noqa: E402

from robot_bridge.ros2.convert import odometry, yaw_to_quaternion  # noqa: E402
from robot_bridge.ros2.fault_injector import LATCHED  # noqa: E402
from robot_bridge.sim import faults, imu, kobuki  # noqa: E402
from robot_bridge.sim import odometry as dead_reckoning  # noqa: E402


class KobukiSim(Node):
    """One simulated Kobuki base."""

    def __init__(self, namespace: str = "", options: object = None, context=None, **overrides) -> None:
        super().__init__("kobuki_sim", namespace=namespace, context=context)
        p = {name: self.declare_parameter(name, overrides.get(name, default)).value for name, default in
             (("rate", 50.0), ("seed", 0), ("x", 0.0), ("y", 0.0), ("yaw", 0.0), ("noise", True),
              ("left_radius_scale", 1.0), ("right_radius_scale", 1.0), ("wheelbase_scale", 1.0),
              ("gyro_bias", 0.0), ("gyro_scale", 0.0))}
        self.dt = 1.0 / float(p["rate"])
        self.rng = np.random.default_rng(int(p["seed"])) if p["noise"] else None
        self.gyro_rng = np.random.default_rng([int(p["seed"]), 2]) if p["noise"] else None
        self.params = kobuki.BaseParams(left_radius_scale=float(p["left_radius_scale"]),
                                        right_radius_scale=float(p["right_radius_scale"]),
                                        wheelbase_scale=float(p["wheelbase_scale"]))
        self.gyro = imu.Gyro(float(p["gyro_bias"]), float(p["gyro_scale"]))
        self.gyro_fault = faults.GyroFaultState()
        self.yaw_rate = 0.0
        self.heading = 0.0
        """The gyro's integrated heading (rad), as the Kobuki's inertial heading."""
        self.state = kobuki.BaseState(x=float(p["x"]), y=float(p["y"]), yaw=float(p["yaw"]))
        self._epoch_ns = self.get_clock().now().nanoseconds
        """Header stamps are this plus the physics' own time, so that a consumer integrating over
        stamps (the odometry node, with the gyro) sees the ``dt`` the physics stepped, even when
        the timer runs late under load; they follow the wall clock while it keeps up."""
        self.fault = faults.NO_FAULT
        self.ticks = kobuki.encoder_ticks(self.state)
        self.odom = dead_reckoning.Odometry(ticks=self.ticks)
        self._command: kobuki.WheelSpeeds | None = None
        self._pub_odom = self.create_publisher(Odometry, "odom", 50)
        self._pub_truth = self.create_publisher(Odometry, "ground_truth", 10)
        self._pub_core = self.create_publisher(String, "sensors/core", 100)
        self._pub_joints = self.create_publisher(JointState, "joint_states", 10)
        self._pub_imu = self.create_publisher(Imu, "sensors/imu_data", 50)
        self.create_subscription(Twist, "commands/velocity", self._on_command, 10)
        self.create_subscription(String, "faults/active", self._on_fault, LATCHED)
        self.create_subscription(Empty, "commands/reset_odometry", self._on_reset, 10)
        self._timer = self.create_timer(self.dt, self._tick)

    def _on_command(self, msg: Twist) -> None:
        self._command = kobuki.twist_to_wheels(msg.linear.x, msg.angular.z)

    def _on_reset(self, msg: Empty) -> None:
        self.odom = dead_reckoning.reset(self.odom)

    def _on_fault(self, msg: String) -> None:
        try:
            self.fault = faults.Fault.parse(msg.data)
        except ValueError as exc:
            self.get_logger().error(f"faults/active: {exc}")

    def _tick(self) -> None:
        command, self._command = self._command, None
        state = faults.apply_to_base(self.fault, self.state)
        self.state = kobuki.step(state, command, self.dt, self.rng, self.params)
        self.ticks = faults.inject_encoders(self.fault, kobuki.encoder_ticks(self.state), self.ticks)
        self.odom = dead_reckoning.update(self.odom, self.ticks, self.dt)
        turned = self.state.yaw - state.yaw
        true_rate = math.atan2(math.sin(turned), math.cos(turned)) / self.dt
        measured = imu.measure(self.gyro, true_rate, self.dt, self.gyro_rng)
        self.yaw_rate, self.gyro_fault = faults.inject_gyro(self.fault, measured, true_rate, self.dt,
                                                            self.gyro_fault)
        self.heading += self.yaw_rate * self.dt
        self._publish()

    def _publish(self) -> None:
        stamp = Time(nanoseconds=self._epoch_ns + round(self.state.time * 1e9)).to_msg()
        s, o = self.state, self.odom
        self._pub_odom.publish(odometry(o.x, o.y, o.yaw, o.speed[0], o.speed[1], stamp))
        v, w = kobuki.wheels_to_twist(kobuki.WheelSpeeds(s.left_speed, s.right_speed))
        self._pub_truth.publish(odometry(s.x, s.y, s.yaw, v, w, stamp, frame_id="world"))
        left_oc, right_oc = kobuki.over_current(s)
        self._pub_core.publish(String(data=json.dumps({
            "time_stamp": int(s.time * 1000) % 65536, "left_encoder": self.ticks[0],
            "right_encoder": self.ticks[1], "over_current": int(left_oc) | int(right_oc) << 1})))
        joints = JointState()
        joints.header.stamp = stamp
        joints.name = ["wheel_left_joint", "wheel_right_joint"]
        joints.position = [self.ticks[0] * kobuki.TICK_TO_RAD, self.ticks[1] * kobuki.TICK_TO_RAD]
        joints.velocity = [s.left_speed, s.right_speed]
        self._pub_joints.publish(joints)
        reading = Imu()
        reading.header.stamp = stamp
        reading.header.frame_id = "gyro_link"
        reading.orientation = yaw_to_quaternion(math.atan2(math.sin(self.heading), math.cos(self.heading)))
        reading.angular_velocity.z = float(self.yaw_rate)
        reading.linear_acceleration_covariance[0] = -1.0     # no accelerometer data (REP 145)
        self._pub_imu.publish(reading)

    def stop(self) -> None:
        self._timer.cancel()


def main(argv: list[str] | None = None) -> int:
    return run_node(KobukiSim, __doc__.splitlines()[0], argv)


if __name__ == "__main__":
    raise SystemExit(main())
