"""Differential-drive physics of one Kobuki base, as a pure step function over explicit state.

Nothing here knows about worlds, threads or time sources: ``step(state, command, dt, rng)`` returns the
next state, so the embedded simulator and the ROS ``kobuki_sim`` node share the same physics.
Constants are the real Kobuki's (``kobuki-base/kobuki_core:src/driver/diff_drive.cpp``, kobuki_ros
parameters): wheelbase 0.23 m, wheel radius 0.035 m, 0.00243691687 rad per encoder tick with unsigned
16-bit counters that wrap, and the base stops when no velocity command arrived for 0.6 s.

Units: metres, radians, seconds inside the physics (degrees only at the agent-facing edges).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

WHEELBASE = 0.23
"""Distance between the two wheels (m)."""
WHEEL_RADIUS = 0.035
"""Wheel radius (m)."""
TICK_TO_RAD = 0.002436916871363930187454
"""Wheel rotation per encoder tick (rad); about 2578.33 ticks per wheel revolution."""
TICKS_PER_REVOLUTION = 2.0 * math.pi / TICK_TO_RAD
ENCODER_MODULUS = 1 << 16
"""Encoders are uint16 counters that wrap around."""
ROBOT_RADIUS = 0.176
"""Half the Kobuki's 351.5 mm diameter (m): the footprint used for collisions."""


class WheelSpeeds(NamedTuple):
    """Angular speeds of the left and right wheels (rad/s), positive = forward."""

    left: float
    right: float


@dataclass(frozen=True)
class BaseParams:
    """Hardware limits of the base; the defaults are the Kobuki's."""

    wheelbase: float = WHEELBASE
    wheel_radius: float = WHEEL_RADIUS
    max_wheel_speed: float = 0.7 / WHEEL_RADIUS
    """The Kobuki's top speed is 0.7 m/s."""
    max_wheel_accel: float = 1.0 / WHEEL_RADIUS
    """Motor acceleration limit (rad/s^2); 1 m/s^2 at the rim."""
    cmd_timeout: float = 0.6
    """kobuki_ros ``cmd_vel_timeout_sec``: without a command for this long the base stops."""
    speed_noise: float = 0.02
    """Relative standard deviation of wheel-speed noise (slip, uneven floor)."""
    left_radius_scale: float = 1.0
    right_radius_scale: float = 1.0
    """True radius of each wheel over ``wheel_radius`` (tyre wear, load, manufacturing): the physics
    drives with the true radii while odometry, like the Kobuki driver, assumes the nominal one."""
    wheelbase_scale: float = 1.0
    """Effective wheelbase in turns over ``wheelbase``: above 1 the tyres scrub (slip) in turns, so
    the robot turns less than its encoders say. 1.0 everywhere: a perfectly calibrated base."""


KOBUKI = BaseParams()

MISCALIBRATION_SIGMA = {"radius": 0.005, "radius_ratio": 0.002, "wheelbase": 0.01}
"""Spread of the systematic wheel-odometry errors drawn by :func:`miscalibrated` (relative)."""
WHEELBASE_SCRUB = 0.03
"""Mean excess of the effective wheelbase in turns (3 %). Sources: UMBmark (Borenstein & Feng 1996)
finds the wheelbase uncertainty the dominant systematic error of differential drives, a few percent,
and the diameter ratio a few tenths of a percent; the Kobuki's tyres are ~2 cm wide on a 23 cm base."""


def miscalibrated(rng: np.random.Generator, params: BaseParams = KOBUKI) -> BaseParams:
    """``params`` with one draw of realistic systematic wheel-odometry error (one robot, one run).

    Mean radius off by N(0, 0.5 %), left/right ratio off by N(0, 0.2 %), effective wheelbase in
    turns N(+3 %, 1 %) larger than nominal (slip in turns). See ``docs/experiments.md``.
    """
    sigma = MISCALIBRATION_SIGMA
    mean = 1.0 + sigma["radius"] * float(rng.standard_normal())
    half_ratio = sigma["radius_ratio"] * float(rng.standard_normal()) / 2.0
    wheelbase = 1.0 + WHEELBASE_SCRUB + sigma["wheelbase"] * float(rng.standard_normal())
    return BaseParams(params.wheelbase, params.wheel_radius, params.max_wheel_speed, params.max_wheel_accel,
                      params.cmd_timeout, params.speed_noise, mean * (1.0 - half_ratio),
                      mean * (1.0 + half_ratio), wheelbase)


@dataclass(frozen=True)
class BaseState:
    """Everything the physics needs to go on: true pose, wheels, and the last command."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0
    """Ground-truth pose in the world (m, m, rad; yaw counter-clockwise from +x)."""
    left_angle: float = 0.0
    right_angle: float = 0.0
    """Total wheel rotation since start (rad): what the encoders count."""
    left_speed: float = 0.0
    right_speed: float = 0.0
    """Current wheel speeds after acceleration limits (rad/s)."""
    target: WheelSpeeds = WheelSpeeds(0.0, 0.0)
    """Last wheel-speed command the motors received."""
    cmd_age: float = math.inf
    """Seconds since that command arrived."""
    blocked: tuple[bool, bool] = (False, False)
    """Wheels that cannot turn (mechanically stuck): the motors push, nothing moves."""
    time: float = 0.0


def twist_to_wheels(linear: float, angular: float, params: BaseParams = KOBUKI) -> WheelSpeeds:
    """Wheel speeds (rad/s) for a body velocity (m/s, rad/s counter-clockwise)."""
    half = angular * params.wheelbase / 2.0
    return WheelSpeeds((linear - half) / params.wheel_radius, (linear + half) / params.wheel_radius)


def wheels_to_twist(wheels: WheelSpeeds, params: BaseParams = KOBUKI) -> tuple[float, float]:
    """Body velocity (m/s, rad/s) of wheel speeds (rad/s)."""
    left = wheels.left * params.wheel_radius
    right = wheels.right * params.wheel_radius
    return (left + right) / 2.0, (right - left) / params.wheelbase


def encoder_ticks(state: BaseState) -> tuple[int, int]:
    """What the encoders read now: uint16 tick counters of the true wheel rotation."""
    return (math.floor(state.left_angle / TICK_TO_RAD) % ENCODER_MODULUS,
            math.floor(state.right_angle / TICK_TO_RAD) % ENCODER_MODULUS)


def tick_difference(current: int, previous: int) -> int:
    """Signed tick change between two uint16 readings, across the wrap (as diff_drive.cpp's (short) cast)."""
    diff = (current - previous) & 0xFFFF
    return diff - ENCODER_MODULUS if diff >= 0x8000 else diff


def _approach(current: float, target: float, max_change: float) -> float:
    return current + max(-max_change, min(max_change, target - current))


def step(state: BaseState, command: WheelSpeeds | None, dt: float,
         rng: np.random.Generator | None = None, params: BaseParams = KOBUKI) -> BaseState:
    """Advance the base by ``dt`` seconds.

    ``command`` is the wheel-speed command that reached the motors during this step (``None``: none
    arrived, the last one stays in force until ``cmd_timeout``). Wheel speeds follow the command under
    the motor acceleration limit; ``rng`` adds wheel-speed noise (``None``: noiseless). The returned
    pose is not checked against obstacles: that is the world's job.
    """
    if command is not None:
        limit = params.max_wheel_speed
        target = WheelSpeeds(max(-limit, min(limit, command.left)), max(-limit, min(limit, command.right)))
        age = 0.0
    else:
        target, age = state.target, state.cmd_age + dt
    effective = target if age < params.cmd_timeout else WheelSpeeds(0.0, 0.0)
    max_change = params.max_wheel_accel * dt
    left = 0.0 if state.blocked[0] else _approach(state.left_speed, effective.left, max_change)
    right = 0.0 if state.blocked[1] else _approach(state.right_speed, effective.right, max_change)
    noisy_left, noisy_right = left, right
    if rng is not None and params.speed_noise > 0.0 and (left or right):
        scale = 1.0 + params.speed_noise * rng.standard_normal(2)
        noisy_left, noisy_right = left * float(scale[0]), right * float(scale[1])
    # Exact arc integration over the step (no drift for pure rotation or straight lines).
    linear, angular = _true_twist(noisy_left, noisy_right, params)
    dyaw = angular * dt
    if abs(dyaw) < 1e-9:
        dx, dy = linear * dt * math.cos(state.yaw), linear * dt * math.sin(state.yaw)
    else:
        radius = linear / angular
        dx = radius * (math.sin(state.yaw + dyaw) - math.sin(state.yaw))
        dy = -radius * (math.cos(state.yaw + dyaw) - math.cos(state.yaw))
    return BaseState(  # built directly: dataclasses.replace costs more than the physics in this hot path
        state.x + dx, state.y + dy, _wrap(state.yaw + dyaw),
        state.left_angle + noisy_left * dt, state.right_angle + noisy_right * dt,
        left, right, target, age, state.blocked, state.time + dt)


def _true_twist(left: float, right: float, params: BaseParams) -> tuple[float, float]:
    """Body velocity the wheels really produce: true radii and effective wheelbase, not the nominal ones."""
    left_v = left * params.wheel_radius * params.left_radius_scale
    right_v = right * params.wheel_radius * params.right_radius_scale
    return (left_v + right_v) / 2.0, (right_v - left_v) / (params.wheelbase * params.wheelbase_scale)


def is_moving(state: BaseState) -> bool:
    """True while either wheel turns."""
    return state.left_speed != 0.0 or state.right_speed != 0.0


def over_current(state: BaseState, params: BaseParams = KOBUKI) -> tuple[bool, bool]:
    """Kobuki's ``over_current`` flags: a motor driven against a wheel that cannot turn."""
    driven = state.cmd_age < params.cmd_timeout
    return (driven and state.blocked[0] and state.target.left != 0.0,
            driven and state.blocked[1] and state.target.right != 0.0)


def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))
