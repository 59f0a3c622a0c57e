"""The one observation vocabulary: a literal such as ``hz(scan)`` or ``~movement(imu,wheel_odom)``,
when it was decided and the measured value that decided it.

Every producer (the observers, the learned ``resource`` detector, a simulator) emits ``Observation`` s;
every consumer (diagnoser, rule engine, agents' percepts, ``/observers/info``) reads them. The name is
the literal's text without spaces, the same name the architecture models declare
(``diagnosis.architecture_yaml``) and ``diagnosis.service.observation_of`` reads.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from diagnosis.service import observation_of

# kind(arg, ...) with atoms as arguments: what an architecture model can declare
_NAME = re.compile(r"[a-z][A-Za-z0-9_]*\([a-z][A-Za-z0-9_]*(,[a-z][A-Za-z0-9_]*)*\)")


def is_observation_name(name: str) -> bool:
    """``hz(scan)`` yes; ``hz(/scan)``, ``Hz(scan)``, ``hz`` no."""
    return _NAME.fullmatch(name) is not None


@dataclass(frozen=True)
class Observation:
    """``name`` observed to hold (``holds``) or not at ``time`` (seconds since the epoch).

    ``measured`` is the value the verdict was decided on (a rate in Hz, a delay in s, a p-value...;
    None when there is none, e.g. ``activated``); ``state`` the configured state that matched (None:
    no state matched); ``source`` the observer (or detector) that emitted it.
    """
    name: str
    holds: bool
    time: float
    measured: float | None = None
    state: str | None = None
    source: str = ""

    @property
    def literal(self) -> str:
        """``hz(scan)`` when it holds, ``~hz(scan)`` when not."""
        return self.name if self.holds else f"~{self.name}"

    @classmethod
    def of(cls, literal: str, time: float, measured: float | None = None, **fields: Any) -> "Observation":
        """From a literal text: ``Observation.of("~hz(scan)", t, 2.9)``."""
        name, holds = observation_of(literal)
        if not is_observation_name(name):
            raise ValueError(f"{literal!r} is not an observation literal like hz(scan) or ~timing(a,b)")
        return cls(name, holds, time, measured, **fields)

    def to_json(self) -> dict[str, Any]:
        return {"observation": self.name, "holds": self.holds, "literal": self.literal, "time": self.time,
                "measured": self.measured, "state": self.state, "source": self.source}
