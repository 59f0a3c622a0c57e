"""The fault injector: it sits between the velocity commands and the base, as in the seed paper.

A fault is a value (``Fault("left_actuator", 0.3)``); the injector functions are pure, so the embedded
simulator and the ROS ``kobuki_sim`` node apply exactly the same faults:

============== ==========================================================================================
kind           effect
============== ==========================================================================================
none           nothing
encoders       wheels turn, the encoders report nothing (their reading stays frozen): odometry sees no motion
both_actuators commands are dropped: the motors receive nothing, the robot does not move
left_actuator  the left wheel runs at ``fraction`` (default 0.3) of its command, so the robot curves left
right_actuator the right wheel runs at ``fraction`` of its command, so the robot curves right
stuck_wheels   both wheels are mechanically blocked: the motors push (Kobuki's over-current flags rise),
               nothing turns
imu_stuck      the gyro reports zero yaw rate from the moment of injection (stuck at zero)
imu_over       the gyro reports 20 % more rotation than it measures (``IMU_OVER_GAIN``)
imu_zero_after the gyro reports zero once the robot has turned without pause for ``ROTATING_FOR_S``
_rotating      (1 s), until the turn ends; short turns still read right (an intermittent fault)
============== ==========================================================================================

The three IMU faults are the seed paper's (Zaman et al., ICRA 2013, section VI).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

from robot_bridge.actions import FAULT_KINDS
from robot_bridge.sim.kobuki import BaseState, WheelSpeeds

DEFAULT_FRACTION = 0.3
IMU_OVER_GAIN = 0.2
"""``imu_over``: rotation overestimated by 20 %, as in the paper."""
ROTATING_FOR_S = 1.0
"""``imu_zero_after_rotating``: seconds of uninterrupted turning after which the gyro reports zero."""
TURNING_RATE = math.radians(5.0)
"""A true yaw rate above this (rad/s) counts as turning for ``imu_zero_after_rotating``."""


@dataclass(frozen=True)
class Fault:
    """One injected fault. ``fraction`` matters only for ``left_actuator`` / ``right_actuator``."""

    kind: str = "none"
    fraction: float = DEFAULT_FRACTION

    def __post_init__(self) -> None:
        if self.kind not in FAULT_KINDS:
            raise ValueError(f"unknown fault {self.kind!r}; expected one of {', '.join(FAULT_KINDS)}")
        if not 0.0 <= self.fraction <= 1.0:
            raise ValueError(f"fault fraction must be within [0, 1], got {self.fraction!r}")

    @classmethod
    def parse(cls, text: str) -> "Fault":
        """``"left_actuator"`` or ``"left_actuator:0.5"`` (the command-line form)."""
        kind, _, fraction = text.partition(":")
        try:
            return cls(kind.strip(), float(fraction) if fraction else DEFAULT_FRACTION)
        except ValueError as exc:
            raise ValueError(f"bad fault {text!r}: {exc}") from None


NO_FAULT = Fault()


def inject_command(fault: Fault, command: WheelSpeeds | None) -> WheelSpeeds | None:
    """The command that reaches the motors when ``command`` is sent (``None``: nothing arrives)."""
    if command is None or fault.kind == "both_actuators":
        return None
    if fault.kind == "left_actuator":
        return WheelSpeeds(command.left * fault.fraction, command.right)
    if fault.kind == "right_actuator":
        return WheelSpeeds(command.left, command.right * fault.fraction)
    return command


def blocked_wheels(fault: Fault) -> tuple[bool, bool]:
    """Which wheels cannot turn under ``fault``."""
    return (True, True) if fault.kind == "stuck_wheels" else (False, False)


def inject_encoders(fault: Fault, true_ticks: tuple[int, int], last_reported: tuple[int, int] | None
                    ) -> tuple[int, int]:
    """The encoder reading the robot's software gets, given what the wheels really did."""
    if fault.kind == "encoders" and last_reported is not None:
        return last_reported
    return true_ticks


def apply_to_base(fault: Fault, state: BaseState) -> BaseState:
    """``state`` with the mechanical part of ``fault`` (blocked wheels) in force."""
    blocked = blocked_wheels(fault)
    if state.blocked == blocked:
        return state
    return replace(state, blocked=blocked)


@dataclass(frozen=True)
class GyroFaultState:
    """What an IMU fault remembers between samples: how long the robot has been turning (s)."""

    turning_for: float = 0.0


def inject_gyro(fault: Fault, reported: float, true_rate: float, dt: float,
                state: GyroFaultState = GyroFaultState()) -> tuple[float, GyroFaultState]:
    """The yaw rate the odometry gets when the gyro measured ``reported`` while the base truly turned
    at ``true_rate`` for ``dt`` s, and the fault's next state."""
    turning_for = state.turning_for + dt if abs(true_rate) > TURNING_RATE else 0.0
    next_state = state if turning_for == state.turning_for else GyroFaultState(turning_for)
    if fault.kind == "imu_stuck":
        return 0.0, next_state
    if fault.kind == "imu_over":
        return reported * (1.0 + IMU_OVER_GAIN), next_state
    if fault.kind == "imu_zero_after_rotating" and turning_for > ROTATING_FOR_S:
        return 0.0, next_state
    return reported, next_state
