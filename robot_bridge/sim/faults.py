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
============== ==========================================================================================
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from robot_bridge.actions import FAULT_KINDS
from robot_bridge.sim.kobuki import BaseState, WheelSpeeds

DEFAULT_FRACTION = 0.3


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
