"""One run of the IMU experiment on real ROS 2 nodes, in real time.

Processes (``robot_bridge.ros2.launch.Supervisor``, a ROS domain of their own): ``kobuki_sim`` (the same
physics, miscalibration and gyro as the embedded run, drawn from the same seed), ``fault_injector``
and the ``odometry`` fusion node. This process is the rest of the robot and the evaluation: the
waypoint controller (on ``ground_truth``, publishing ``commands/velocity_raw``), the observers fed
from real subscriptions to ``sensors/imu_data`` and ``odom`` (remapped onto the observer config's
``/imu`` and ``/wheel_odom``), the diagnoser and the rule, whose ``set_parameter`` reaches the
odometry node through its real ``set_parameters`` service. The fault is set the same way on
``fault_injector``. The always-IMU odometry is the node's fusion fed from the same topics here.
"""
from __future__ import annotations

import math
import os
import threading
import time

import numpy as np

from experiments.imu_detection import Detection
from experiments.imu_result import RunResult, Sample
from experiments.waypoints import Route
from robot_bridge.sim import imu, kobuki
from robot_bridge.sim.odometry_fusion import OdometryFusion

ROBOT = "imu_robot"
CONTROL_PERIOD = 0.1


def default_domain_id() -> int:
    """A domain of our own (1..100 keeps Fast DDS off the ephemeral ports), unless ROS_DOMAIN_ID is set."""
    return int(os.environ["ROS_DOMAIN_ID"]) if "ROS_DOMAIN_ID" in os.environ else 1 + os.getpid() % 100


def node_specs(seed: int) -> list:
    """The robot's node processes, with this seed's miscalibration and gyro residuals."""
    from robot_bridge.ros2.launch import NodeSpec
    rng = np.random.default_rng([seed, 7])
    params = kobuki.miscalibrated(rng)
    gyro = imu.Gyro.draw(np.random.default_rng([seed, 8]))
    base = (("seed", str(seed)), ("left_radius_scale", repr(params.left_radius_scale)),
            ("right_radius_scale", repr(params.right_radius_scale)),
            ("wheelbase_scale", repr(params.wheelbase_scale)),
            ("gyro_bias", repr(gyro.bias)), ("gyro_scale", repr(gyro.scale)))
    return [NodeSpec(ROBOT, "kobuki_sim", base), NodeSpec(ROBOT, "fault_injector"), NodeSpec(ROBOT, "odometry")]


class _Driver:
    """Everything of the run that lives in this process; callbacks run on the executor thread."""

    def __init__(self, ros, parameters, fault: str, fault_time: float, duration: float) -> None:
        import rclpy
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from sensor_msgs.msg import Imu

        from robot_bridge.ros2.odometry import Increments

        self.node = ros.add(rclpy.create_node("imu_experiment", namespace=f"/{ROBOT}", context=ros.context))
        self.parameters = parameters
        """``detection.taps.ros2_parameters.Ros2Parameters``: its own context, so a rule firing in
        our executor's callback can wait for the service answer."""
        self.fault, self.fault_time, self.duration = fault, fault_time, duration
        self.lock = threading.Lock()
        self.latest: dict[str, object] = {}
        self.samples: list[Sample] = []
        self.switch_time: float | None = None
        self.start: float | None = None
        self.injected = fault == "none"
        self.errors: list[str] = []
        self.route = Route()
        self.always = OdometryFusion(use_imu=True)
        self.increments = Increments()
        self.detection = Detection(self._set_parameter)
        self.twist = Twist
        self.cmd = self.node.create_publisher(Twist, "commands/velocity_raw", 10)
        self.node.create_subscription(Odometry, "ground_truth", lambda m: self._keep("truth", m), 10)
        self.node.create_subscription(Odometry, "odometry/fused", lambda m: self._keep("fused", m), 50)
        self.node.create_subscription(Imu, "sensors/imu_data", self._on_imu, 100)
        self.node.create_subscription(Odometry, "odom", self._on_wheel_odometry, 100)
        self.timer = None

    def ready(self) -> bool:
        return {"truth", "fused", "wheel"} <= set(self.latest)

    def begin(self) -> None:
        self.start = time.monotonic()
        self.timer = self.node.create_timer(CONTROL_PERIOD, self._control)

    def now(self) -> float:
        return time.monotonic() - self.start if self.start is not None else 0.0

    def _keep(self, key: str, msg) -> None:
        self.latest[key] = msg

    def _set_parameter(self, node: str, name: str, value) -> None:
        """The rule's action: the model's node names are the robot's nodes, in its namespace."""
        self.parameters.set_parameter(f"/{ROBOT}/{node}", name, value)
        if self.switch_time is None:
            self.switch_time = self.now()

    def _on_imu(self, msg) -> None:
        self.increments.imu(msg)
        if self.start is not None:
            self.detection.feed("/imu", self.now(), msg)

    def _on_wheel_odometry(self, msg) -> None:
        self.latest["wheel"] = msg
        step = self.increments.wheel_odometry(msg)
        if step is not None:
            self.always.step(*step)
        if self.start is not None:
            self.detection.feed("/wheel_odom", self.now(), msg)

    def _control(self) -> None:
        from robot_bridge.ros2.convert import pose_of
        now = self.now()
        try:
            if not self.injected and now >= self.fault_time:
                self.parameters.set_parameter(f"/{ROBOT}/fault_injector", "fault", self.fault)
                self.injected = True
        except Exception as exc:          # noqa: BLE001 - reported as the run's error, never lost
            self.errors.append(f"could not inject {self.fault}: {exc}")
        truth = pose_of(self.latest["truth"])
        v, w = self.route.command(truth)
        msg = self.twist()
        msg.linear.x, msg.angular.z = float(v), float(w)
        self.cmd.publish(msg)
        wheel, fused = pose_of(self.latest["wheel"]), pose_of(self.latest["fused"])
        self.samples.append(Sample(now, truth[:2], wheel[:2], (self.always.pose.x, self.always.pose.y), fused[:2]))


def run(fault: str, fault_time: float, seed: int, duration: float, domain_id: int | None = None,
        ready_timeout: float = 60.0) -> RunResult:
    """Drive ``duration`` wall-clock seconds on the real nodes; raises ``RuntimeError`` if they fail."""
    from detection.taps.ros2_parameters import Ros2Parameters
    from robot_bridge.ros2.launch import Supervisor
    from robot_bridge.ros2.runtime import RosContext

    domain = default_domain_id() if domain_id is None else domain_id
    supervisor = Supervisor(node_specs(seed), domain)
    supervisor.start()
    try:
        missing = supervisor.wait_ready(ready_timeout)
        if missing or supervisor.dead():
            raise RuntimeError(f"ROS 2 nodes did not come up in domain {domain}: "
                               f"{', '.join(sorted(n for n, _ in missing)) or 'a node exited'}")
        parameters = Ros2Parameters(domain_id=domain, timeout=10.0)
        try:
            with RosContext(domain_id=domain) as ros:
                driver = _Driver(ros, parameters, fault, fault_time, duration)
                try:
                    _drive(driver, supervisor, duration, domain)
                finally:
                    driver.detection.close()
        finally:
            parameters.close()
    finally:
        supervisor.stop()
    return RunResult(fault, fault_time if fault != "none" else None, seed, list(driver.samples),
                     driver.switch_time, driver.detection.cpu_seconds, duration, driver.route.reached)


def _drive(driver: _Driver, supervisor, duration: float, domain: int) -> None:
    from robot_bridge.ros2.runtime import wait_for

    if not wait_for(driver.ready, 30.0):
        raise RuntimeError(f"no messages from the robot's nodes in domain {domain} within 30 s "
                           f"(seen: {', '.join(driver.latest) or 'none'})")
    driver.begin()
    end = time.monotonic() + duration
    while time.monotonic() < end:
        if supervisor.dead():
            spec, code = supervisor.dead()[0]
            raise RuntimeError(f"{spec.node} exited with code {code} during the run")
        time.sleep(0.2)
    driver.timer.cancel()
    driver.cmd.publish(driver.twist())
    if driver.errors:
        raise RuntimeError("; ".join(driver.errors))
