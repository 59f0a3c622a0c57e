"""The warehouse round of the IMU experiment: six waypoints and the controller that drives between them.

The controller steers on a localized pose (in the simulators: ground truth, standing in for the
map-based localization the paper's robot navigated with), so every run drives the same kind of path
whatever the odometries believe, and the three odometries are compared on exactly the same motion.
It turns in place towards the next waypoint when far off its heading and drives in gentle arcs
otherwise, as a differential-drive robot on a planner does. Pure functions: both bridges use them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

WAYPOINTS: tuple[tuple[float, float], ...] = (
    (0.0, 0.0), (3.5, 0.0), (3.5, 2.5), (0.5, 3.0), (-1.0, 1.0), (1.5, 1.2))
"""A round through a 4.5 m x 3 m warehouse bay, visited in order, again and again; the last leg
turns right where the others turn left, so both turn directions occur."""


@dataclass(frozen=True)
class ControllerParams:
    cruise: float = 0.3
    """m/s on straight legs (the Kobuki's comfortable indoor speed)."""
    turn_rate: float = math.radians(60.0)
    """Fastest turn (rad/s), well within the gyro's 110 deg/s."""
    turn_in_place: float = math.radians(25.0)
    """Heading error above which the robot stops and turns in place."""
    heading_gain: float = 2.0
    reached: float = 0.12
    """A waypoint counts as reached within this distance (m)."""


DEFAULT = ControllerParams()


def command(pose: tuple[float, float, float], goal: tuple[float, float],
            params: ControllerParams = DEFAULT) -> tuple[float, float]:
    """Velocity command (m/s, rad/s) from ``pose`` (x, y, yaw rad) towards ``goal``."""
    x, y, yaw = pose
    dx, dy = goal[0] - x, goal[1] - y
    error = math.atan2(dy, dx) - yaw
    error = math.atan2(math.sin(error), math.cos(error))
    angular = max(-params.turn_rate, min(params.turn_rate, params.heading_gain * error))
    if abs(error) > params.turn_in_place:
        return 0.0, angular
    distance = math.hypot(dx, dy)
    return min(params.cruise, 0.8 * distance + 0.05), angular


class Route:
    """Where the robot is going next; advances when the current waypoint is reached."""

    def __init__(self, waypoints: tuple[tuple[float, float], ...] = WAYPOINTS,
                 params: ControllerParams = DEFAULT) -> None:
        self.waypoints, self.params = waypoints, params
        self.index = 1 % len(waypoints)
        self.reached = 0

    def command(self, pose: tuple[float, float, float]) -> tuple[float, float]:
        goal = self.waypoints[self.index]
        if math.hypot(goal[0] - pose[0], goal[1] - pose[1]) < self.params.reached:
            self.index = (self.index + 1) % len(self.waypoints)
            self.reached += 1
            goal = self.waypoints[self.index]
        return command(pose, goal, self.params)
