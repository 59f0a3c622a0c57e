"""THE action vocabulary: what a plan may ask any robot to do, with units and completion rules.

Every bridge accepts exactly these actions (a bridge that cannot do one answers ``unsupported``) and
checks them with ``check`` before doing anything, so an unknown action or malformed arguments fail at
once, identically on every bridge. Units: metres, degrees, seconds; angles counter-clockwise (left)
positive, as in ROS (REP 103).

=========================== ============================================================================
action                      meaning and completion
=========================== ============================================================================
``move(M)``                 drive straight ``M`` metres (negative: backwards) at 0.2 m/s; succeeds when the
``move(M, MPerS)``          robot's own odometry has driven ``|M|`` (within 5 mm)
``turn(D)``                 rotate in place by ``D`` degrees at 45 deg/s; succeeds when odometry has turned
``turn(D, DPerS)``          ``D`` (within 0.5 degree)
``rotate(DPerS)``           start a continuous rotation in place (searching for a partner): succeeds once
                            odometry shows the rotation under way; it goes on until ``stop`` or another
                            motion
``stop``                    decelerate to a standstill; succeeds when odometry shows the robot still
``reset_odometry``          set the believed pose back to (0, 0, 0); succeeds at once
``set_fault(K)``            inject fault ``K`` (``none``, ``encoders``, ``both_actuators``, ``left_actuator``,
``set_fault(K, Fraction)``  ``right_actuator``, ``stuck_wheels``, ``imu_stuck``, ``imu_over``,
                            ``imu_zero_after_rotating``; see ``robot_bridge.sim.faults``) for tests
                            and experiments; succeeds at once; real robots answer ``unsupported``
=========================== ============================================================================

One motion runs at a time: a new motion (``move``, ``turn``, ``rotate``, ``stop``) preempts the
running one, which fails with ``preempted``. Failure reasons are the words in ``REASONS``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from robot_bridge.protocol import Action, Completion, Value

REASONS: dict[str, str] = {
    "unknown_action": "no action of that name and arity in robot_bridge.actions.ACTIONS",
    "bad_args": "an argument has the wrong type or is out of range",
    "timeout": "the motion did not finish within its time bound, or the robot did not answer",
    "no_progress": "the robot's own odometry showed no progress towards the goal for a while",
    "bumper": "the bumper was pressed while driving",
    "preempted": "another motion replaced this one",
    "unsupported": "this bridge cannot perform this (valid) action",
    "shutdown": "the bridge shut down before the action finished",
}
"""Every failure reason a bridge may give, with its meaning."""

FAULT_KINDS: tuple[str, ...] = (  # what each does: robot_bridge.sim.faults
    "none", "encoders", "both_actuators", "left_actuator", "right_actuator", "stuck_wheels",
    "imu_stuck", "imu_over", "imu_zero_after_rotating")


@dataclass(frozen=True)
class Param:
    """One argument: a number within ``[low, high]`` in ``unit``, or an atom among ``choices``."""

    name: str
    unit: str = ""
    low: float = -math.inf
    high: float = math.inf
    choices: tuple[str, ...] = ()
    default: Value | None = None
    """Value used when an optional trailing argument is left out."""

    def check(self, value: Value) -> str | None:
        """Why ``value`` is not acceptable, or ``None``."""
        if self.choices:
            if not isinstance(value, str) or value not in self.choices:
                return f"{self.name} must be one of {', '.join(self.choices)}, got {value!r}"
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            return f"{self.name} must be a finite number ({self.unit}), got {value!r}"
        if not self.low <= value <= self.high:
            return f"{self.name} must be within [{self.low:g}, {self.high:g}] {self.unit}, got {value!r}"
        return None


@dataclass(frozen=True)
class ActionSpec:
    """An action of the vocabulary; trailing parameters with a ``default`` are optional."""

    name: str
    params: tuple[Param, ...]
    motion: bool
    """True for actions that drive the wheels (and preempt each other)."""
    doc: str

    @property
    def min_arity(self) -> int:
        return sum(1 for p in self.params if p.default is None)


ACTIONS: dict[str, ActionSpec] = {spec.name: spec for spec in (
    ActionSpec("move", (Param("Metres", "m", -100.0, 100.0),
                        Param("MetresPerSecond", "m/s", 0.01, 0.7, default=0.2)), True,
               "drive straight; negative distance drives backwards"),
    ActionSpec("turn", (Param("Degrees", "deg", -3600.0, 3600.0),
                        Param("DegreesPerSecond", "deg/s", 1.0, 180.0, default=45.0)), True,
               "rotate in place, counter-clockwise positive"),
    ActionSpec("rotate", (Param("DegreesPerSecond", "deg/s", -180.0, 180.0),), True,
               "rotate in place until stop or another motion (search)"),
    ActionSpec("stop", (), True, "decelerate to a standstill"),
    ActionSpec("reset_odometry", (), False, "believed pose back to the origin"),
    ActionSpec("set_fault", (Param("Kind", choices=FAULT_KINDS),
                             Param("Fraction", "", 0.0, 1.0, default=0.3)), False,
               "inject a fault (simulated robots only)"),
)}


class ActionError(ValueError):
    """An action that cannot be started; ``reason`` is ``unknown_action`` or ``bad_args``."""

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason


def normalize(action: Action) -> tuple[ActionSpec, tuple[Value, ...]]:
    """The action's spec and its full argument tuple (defaults filled in); raises ``ActionError``."""
    spec = ACTIONS.get(action.name)
    if spec is None:
        known = ", ".join(sorted(ACTIONS))
        raise ActionError("unknown_action", f"unknown action {action.name!r}; known actions: {known}")
    if not spec.min_arity <= len(action.args) <= len(spec.params):
        arity = (str(len(spec.params)) if spec.min_arity == len(spec.params)
                 else f"{spec.min_arity} to {len(spec.params)}")
        raise ActionError("bad_args",
                          f"{action.name} takes {arity} arguments, got {len(action.args)} in {action}")
    for param, value in zip(spec.params, action.args):
        problem = param.check(value)
        if problem:
            raise ActionError("bad_args", f"{action}: {problem}")
    defaults = tuple(p.default for p in spec.params[len(action.args):])
    return spec, tuple(action.args) + defaults  # type: ignore[operator]


def check(action: Action) -> Completion | None:
    """The immediate failure for a malformed action, or ``None`` if it may start."""
    try:
        normalize(action)
    except ActionError as exc:
        return Completion.failure(exc.reason, str(exc))
    return None
