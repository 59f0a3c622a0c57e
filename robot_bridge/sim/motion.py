"""Motion decomposition: ``move``, ``turn``, ``rotate`` and ``stop`` become wheel-speed commands.

The robot's own odometry, never ground truth, decides completion. That is how a robot discovers its
own faults: with the encoders dead, odometry shows no progress and ``move`` fails with ``no_progress``
while the robot in fact drives on; with a weak actuator it curves but odometry still counts the path.

Pure functions over explicit state: ``start`` builds a ``MotionState``; ``control`` is called every
control step with the latest odometry and returns the next state, the wheel command to send (``None``:
send nothing) and, once, the ``Completion`` of the action.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from robot_bridge.protocol import Completion
from robot_bridge.sim.kobuki import KOBUKI, BaseParams, WheelSpeeds, twist_to_wheels
from robot_bridge.sim.odometry import Odometry


@dataclass(frozen=True)
class MotionLimits:
    """The velocity smoother and the completion rules (units: m, rad, s)."""

    linear_accel: float = 0.5
    angular_accel: float = 2.0
    distance_tolerance: float = 0.005
    angle_tolerance: float = math.radians(0.5)
    creep_linear: float = 0.02
    """Slowest speed near the goal, so the approach does not crawl forever."""
    creep_angular: float = math.radians(4.0)
    stall_window: float = 1.0
    """``no_progress`` when odometry has not advanced for this long."""
    stall_distance: float = 0.005
    stall_angle: float = math.radians(0.5)
    timeout_factor: float = 2.0
    """Time bound = ``timeout_factor`` x the nominal duration + ``timeout_margin``."""
    timeout_margin: float = 2.0
    still_linear: float = 0.002
    still_angular: float = math.radians(0.5)
    rotate_confirm: float = math.radians(2.0)
    """``rotate`` succeeds once odometry has turned this far in the requested direction."""


DEFAULT_LIMITS = MotionLimits()


class MotionState(NamedTuple):
    """A motion in progress: its goal, progress bookkeeping and the smoothed velocity command.

    A NamedTuple rather than a frozen dataclass: ``_replace`` is cheap enough for every control step.
    """

    kind: str
    goal: float
    """Signed distance (m) for ``move``, signed angle (rad) for ``turn``, signed speed for ``rotate``."""
    speed: float
    """Cruise speed magnitude (m/s or rad/s)."""
    origin: float
    """Odometry distance (move) or rotation (turn, rotate) when the motion started."""
    started: float
    deadline: float
    best: float = 0.0
    best_time: float = 0.0
    linear: float = 0.0
    angular: float = 0.0
    finished: bool = False
    """True once the action's completion was reported (``rotate`` keeps turning after that)."""


def start(kind: str, args: tuple, odom: Odometry, now: float, current: tuple[float, float] = (0.0, 0.0),
          limits: MotionLimits = DEFAULT_LIMITS) -> MotionState:
    """Begin ``kind`` with normalized ``args`` (see ``robot_bridge.actions``) from velocity ``current``."""
    linear, angular = current
    if kind == "move":
        goal, speed = float(args[0]), float(args[1])
        nominal = abs(goal) / speed + speed / limits.linear_accel
        origin = odom.distance
    elif kind == "turn":
        goal, speed = math.radians(float(args[0])), math.radians(float(args[1]))
        nominal = abs(goal) / speed + speed / limits.angular_accel
        origin = odom.rotation
    elif kind == "rotate":
        goal = math.radians(float(args[0]))
        speed = abs(goal)
        nominal = limits.rotate_confirm / max(speed, 1e-6) + speed / limits.angular_accel
        origin = odom.rotation
    elif kind == "stop":
        goal, speed, origin = 0.0, 0.0, 0.0
        nominal = abs(linear) / limits.linear_accel + abs(angular) / limits.angular_accel
    else:
        raise ValueError(f"not a motion: {kind!r}")
    deadline = now + limits.timeout_factor * min(nominal, 1e6) + limits.timeout_margin
    return MotionState(kind, goal, speed, origin, now, deadline, 0.0, now, linear, angular)


def _ramp(current: float, desired: float, accel: float, dt: float) -> float:
    return current + max(-accel * dt, min(accel * dt, desired - current))


def _progress(motion: MotionState, odom: Odometry) -> float:
    measure = odom.distance if motion.kind == "move" else odom.rotation
    return (measure - motion.origin) * math.copysign(1.0, motion.goal)


def control(motion: MotionState, odom: Odometry, now: float, dt: float, bumper: bool = False,
            limits: MotionLimits = DEFAULT_LIMITS, params: BaseParams = KOBUKI
            ) -> tuple[MotionState | None, WheelSpeeds | None, Completion | None]:
    """One control step: (next state or ``None`` when done, wheel command, completion if it ended now)."""
    if motion.kind == "stop":
        linear = _ramp(motion.linear, 0.0, limits.linear_accel, dt)
        angular = _ramp(motion.angular, 0.0, limits.angular_accel, dt)
        still = (abs(odom.speed[0]) < limits.still_linear and abs(odom.speed[1]) < limits.still_angular)
        if linear == 0.0 and angular == 0.0 and still:
            return None, WheelSpeeds(0.0, 0.0), Completion.success()
        if now > motion.deadline:
            return None, WheelSpeeds(0.0, 0.0), Completion.failure("timeout", "the robot did not come to rest")
        return motion._replace(linear=linear, angular=angular), twist_to_wheels(linear, angular, params), None

    if motion.kind in ("move", "turn") and motion.goal == 0.0:
        return None, None, Completion.success()
    progress = _progress(motion, odom)
    best, best_time = motion.best, motion.best_time
    threshold = limits.stall_distance if motion.kind == "move" else limits.stall_angle
    if progress > best + threshold:
        best, best_time = progress, now

    if motion.kind == "rotate":
        angular = _ramp(motion.angular, motion.goal, limits.angular_accel, dt)
        linear = _ramp(motion.linear, 0.0, limits.linear_accel, dt)
        nxt = motion._replace(best=best, best_time=best_time, linear=linear, angular=angular)
        command = twist_to_wheels(linear, angular, params)
        if motion.finished:
            return nxt, command, None
        if motion.goal == 0.0 or progress >= limits.rotate_confirm:
            return nxt._replace(finished=True), command, Completion.success()
        failure = _stalled(motion, now, best_time, limits)
        return (None, WheelSpeeds(0.0, 0.0), failure) if failure else (nxt, command, None)

    is_move = motion.kind == "move"
    remaining = abs(motion.goal) - progress
    tolerance = limits.distance_tolerance if is_move else limits.angle_tolerance
    if remaining <= tolerance:
        return None, WheelSpeeds(0.0, 0.0), Completion.success()
    if is_move and bumper and motion.goal > 0:
        return None, WheelSpeeds(0.0, 0.0), Completion.failure("bumper", f"after {progress:.2f} m")
    failure = _stalled(motion, now, best_time, limits)
    if failure:
        return None, WheelSpeeds(0.0, 0.0), failure
    accel = limits.linear_accel if is_move else limits.angular_accel
    creep = limits.creep_linear if is_move else limits.creep_angular
    cruise = min(motion.speed, max(creep, math.sqrt(2.0 * accel * remaining)))
    desired = math.copysign(cruise, motion.goal)
    if is_move:
        linear = _ramp(motion.linear, desired, accel, dt)
        angular = _ramp(motion.angular, 0.0, limits.angular_accel, dt)
    else:
        linear = _ramp(motion.linear, 0.0, limits.linear_accel, dt)
        angular = _ramp(motion.angular, desired, accel, dt)
    nxt = motion._replace(best=best, best_time=best_time, linear=linear, angular=angular)
    return nxt, twist_to_wheels(linear, angular, params), None


def _stalled(motion: MotionState, now: float, best_time: float, limits: MotionLimits) -> Completion | None:
    if now - best_time > limits.stall_window:
        return Completion.failure(
            "no_progress", f"odometry showed no progress for {limits.stall_window:g} s")
    if now > motion.deadline:
        return Completion.failure("timeout", f"not done after {now - motion.started:.1f} s")
    return None
