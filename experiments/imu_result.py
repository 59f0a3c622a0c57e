"""What one run of the IMU experiment yields, and the error figures the paper reports for it."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

ODOMETRIES = ("encoders", "always_imu", "switched")
"""The three odometries compared on every run: encoders only, always fusing the IMU, and fusing it
until the rule switches the IMU off."""


class Sample(NamedTuple):
    """Ground truth and the three odometries' positions (m) at one time (s)."""

    time: float
    truth: tuple[float, float]
    encoders: tuple[float, float]
    always_imu: tuple[float, float]
    switched: tuple[float, float]


@dataclass(frozen=True)
class RunResult:
    fault: str
    fault_time: float | None
    seed: int
    samples: list[Sample]
    switch_time: float | None
    """When the rule set ``use_imu`` false (simulated or wall s since start), None if it never fired."""
    cpu_seconds: float
    """CPU spent in observers + diagnosis + rules over the run."""
    duration: float
    waypoints_reached: int = 0

    def errors(self, odometry: str) -> list[float]:
        """Position error (m) of ``odometry`` at every sample."""
        return [math.dist(getattr(s, odometry), s.truth) for s in self.samples]

    def mean_error(self, odometry: str) -> float:
        errors = self.errors(odometry)
        return sum(errors) / len(errors)

    def rms_error(self, odometry: str) -> float:
        errors = self.errors(odometry)
        return math.sqrt(sum(e * e for e in errors) / len(errors))

    @property
    def latency(self) -> float | None:
        """Fault start -> rule fired (s); None without a fault or a switch."""
        if self.fault_time is None or self.switch_time is None:
            return None
        return self.switch_time - self.fault_time

    @property
    def false_switch(self) -> bool:
        """The rule fired on a healthy run, or before the fault began."""
        return self.switch_time is not None and (self.fault_time is None or self.switch_time < self.fault_time)

    @property
    def cpu_share(self) -> float:
        """CPU of observers + diagnosis + rules as a share of one core over the observed time."""
        return self.cpu_seconds / self.duration if self.duration > 0 else 0.0
