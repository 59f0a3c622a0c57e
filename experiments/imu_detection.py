"""The IMU experiment's detect -> diagnose -> react chain, built from its three files (package data).

``imu_odometry.observers.yaml`` (one movement observer), ``imu_odometry.yaml`` (the architecture
model) and ``imu_odometry.rules.yaml`` (``~movement(imu,wheel_odom)`` and ``imu`` in PosAb ->
``set_parameter(odometry, use_imu, false)``), wired with the ``detection`` package's API. The
caller hands in the parameter setter the rule's action reaches: the simulated robot's, or a real ROS 2
node's. CPU time spent here is counted, so the experiment reports the share of one core it costs.
"""
from __future__ import annotations

import time
from importlib import resources
from pathlib import Path
from typing import Any, Callable

from detection.config import load_observers
from detection.message import Message
from detection.pipeline import Pipeline, Update
from diagnosis.actions import ActionEnvironment
from diagnosis.loader import load_model
from diagnosis.rules import load_rules

IMU_CHANNEL = "/imu"
WHEEL_CHANNEL = "/wheel_odom"
"""The channels the observer config names; a ROS 2 run remaps the robot's real topics onto them."""


def data_file(name: str) -> Path:
    """One of the experiment's files, shipped as package data next to this module."""
    return Path(str(resources.files("experiments") / name))


MODEL = "imu_odometry.yaml"
RULES = "imu_odometry.rules.yaml"
OBSERVERS = "imu_odometry.observers.yaml"


class _Setter:
    def __init__(self, set_parameter: Callable[[str, str, Any], None]) -> None:
        self.set_parameter = set_parameter


class Detection:
    """Observers + diagnoser + rules for one run; ``feed`` one message at a time, in time order."""

    def __init__(self, set_parameter: Callable[[str, str, Any], None], log: Callable[[Update], None] | None = None
                 ) -> None:
        start = time.thread_time()
        self.observers = load_observers(data_file(OBSERVERS)).build()
        model = load_model(data_file(MODEL))
        self.pipeline = Pipeline(model, load_rules(data_file(RULES), model),
                                 ActionEnvironment(parameters=_Setter(set_parameter)))
        if log is not None:
            self.pipeline.add_listener(log)
        self.setup_cpu_seconds = time.thread_time() - start
        self.cpu_seconds = 0.0
        """CPU of feeding, observing, diagnosing and running rules (set-up not included)."""

    def feed(self, channel: str, t: float, data: Any) -> None:
        """One message (decoded data, e.g. an rclpy ``Imu`` or a dict) received at ``t`` seconds."""
        start = time.thread_time()
        changed = self.observers.feed(Message(channel, int(round(t * 1e9)), data))
        if changed:
            self.pipeline.observe(changed)
        self.cpu_seconds += time.thread_time() - start

    def feed_imu(self, t: float, yaw_rate: float) -> None:
        self.feed(IMU_CHANNEL, t, {"angular_velocity": {"z": yaw_rate}})

    def feed_wheels(self, t: float, yaw_rate: float) -> None:
        self.feed(WHEEL_CHANNEL, t, {"twist": {"twist": {"angular": {"z": yaw_rate}}}})

    def close(self) -> None:
        self.pipeline.close()
