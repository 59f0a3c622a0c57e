"""The odometry component that fuses wheel odometry with the IMU: the gyro's rotation replaces the
encoders' rotation, the encoders still give the distance (as the Kobuki driver's ``use_imu_heading``).

One class for both worlds: the embedded simulator steps it with each sample, the ROS 2 node
``robot_bridge.ros2.odometry_fusion`` with each wheel-odometry message. Its parameter ``use_imu``
(default true) is what a repair rule switches off when the IMU is blamed; switching keeps the
current pose and only changes where later rotation comes from.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

PARAMETERS = ("use_imu",)


@dataclass(frozen=True)
class Pose2D:
    """A planar pose (m, m, rad)."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0


def advance(pose: Pose2D, distance: float, rotation: float) -> Pose2D:
    """``pose`` after driving ``distance`` m while turning ``rotation`` rad (mid-point heading)."""
    mid = pose.yaw + rotation / 2.0
    yaw = pose.yaw + rotation
    return Pose2D(pose.x + distance * math.cos(mid), pose.y + distance * math.sin(mid),
                  math.atan2(math.sin(yaw), math.cos(yaw)))


class OdometryFusion:
    """Dead reckoning from wheel distance and either the gyro's or the encoders' rotation."""

    def __init__(self, pose: Pose2D = Pose2D(), use_imu: bool = True) -> None:
        self.pose = pose
        self.use_imu = bool(use_imu)

    def step(self, distance: float, wheel_rotation: float, imu_rotation: float) -> Pose2D:
        """Integrate one sample: wheel distance (m), the encoders' and the gyro's rotation (rad)."""
        self.pose = advance(self.pose, distance, imu_rotation if self.use_imu else wheel_rotation)
        return self.pose

    def set_parameter(self, name: str, value: Any) -> None:
        """Set a parameter by name (``use_imu``: a bool, or its text ``true``/``false``)."""
        if name != "use_imu":
            raise KeyError(f"odometry has no parameter {name!r} (parameters: {', '.join(PARAMETERS)})")
        self.use_imu = parse_bool(value)


def parse_bool(value: Any) -> bool:
    """A parameter value as a bool: ``True``/``False`` or the texts true/false (any case)."""
    if isinstance(value, bool):
        return value
    text = str(value).strip().lower()
    if text in ("true", "false"):
        return text == "true"
    raise ValueError(f"expected true or false, got {value!r}")
