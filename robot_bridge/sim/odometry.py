"""The robot's own odometry: dead reckoning from encoder ticks, as the Kobuki driver does it.

This is what the robot *believes*; it differs from ground truth by wheel-speed noise and, under an
``encoders`` fault, by everything (the encoders report nothing, so odometry stands still while the
robot drives). Motion completion is judged on this, never on ground truth.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from robot_bridge.sim.kobuki import KOBUKI, TICK_TO_RAD, BaseParams, tick_difference


@dataclass(frozen=True)
class Odometry:
    """Believed pose (m, m, rad) and the last encoder reading it integrated."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0
    ticks: tuple[int, int] | None = None
    distance: float = 0.0
    """Signed path length driven since start (m): the progress measure of ``move``."""
    rotation: float = 0.0
    """Unwrapped heading change since start (rad): the progress measure of ``turn``."""
    speed: tuple[float, float] = (0.0, 0.0)
    """Last measured body velocity (m/s, rad/s)."""


def update(odom: Odometry, ticks: tuple[int, int], dt: float, params: BaseParams = KOBUKI) -> Odometry:
    """Integrate a new encoder reading taken ``dt`` seconds after the previous one."""
    if odom.ticks is None:
        return Odometry(odom.x, odom.y, odom.yaw, ticks, odom.distance, odom.rotation)
    left = tick_difference(ticks[0], odom.ticks[0]) * TICK_TO_RAD * params.wheel_radius
    right = tick_difference(ticks[1], odom.ticks[1]) * TICK_TO_RAD * params.wheel_radius
    ds = (left + right) / 2.0
    dyaw = (right - left) / params.wheelbase
    mid = odom.yaw + dyaw / 2.0
    yaw = math.atan2(math.sin(odom.yaw + dyaw), math.cos(odom.yaw + dyaw))
    speed = (ds / dt, dyaw / dt) if dt > 0 else odom.speed
    return Odometry(odom.x + ds * math.cos(mid), odom.y + ds * math.sin(mid), yaw, ticks,
                    odom.distance + ds, odom.rotation + dyaw, speed)


def reset(odom: Odometry) -> Odometry:
    """Odometry back to the origin, keeping the encoder reference (Kobuki's ``reset_odometry``)."""
    return Odometry(ticks=odom.ticks)
