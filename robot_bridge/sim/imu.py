"""The base's yaw-rate gyro (the IMU odometry fuses), as a pure function of the true yaw rate.

A reading is ``(1 + scale) * true_rate + bias + white noise``, clipped to the range and quantized to
the resolution. ``scale`` and ``bias`` are drawn once per robot (what the factory and the start-up
calibration leave), the noise every sample. Figures and their sources (also in docs/experiments.md):

- range +-110 deg/s and resolution 0.01 deg/s: the Kobuki's factory-calibrated single-axis gyro
  (Kobuki user guide, "Gyro: factory calibrated, 1 axis (110 deg/s)"; kobuki_core reports the
  angle rate in hundredths of a degree per second);
- noise density 0.03 deg/s/sqrt(Hz): the rate noise density of the ST L3G4200D, the Kobuki's 3-axis
  MEMS gyro, and typical of consumer MEMS gyros; per sample of ``dt`` seconds the standard deviation
  is ``density / sqrt(dt)`` (its integral is the datasheet's angle random walk);
- residual bias N(0, 0.01 deg/s): what remains after the Kobuki's calibration at rest on start-up,
  of the order of a consumer MEMS gyro's bias instability (10-40 deg/h);
- scale-factor error N(0, 0.3 %): a factory-calibrated sensitivity (uncalibrated MEMS parts are
  specified to a few percent).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

DEG = math.pi / 180.0


@dataclass(frozen=True)
class GyroParams:
    """The gyro's datasheet figures (SI units: rad/s)."""

    range: float = 110.0 * DEG
    resolution: float = 0.01 * DEG
    noise_density: float = 0.03 * DEG
    """rad/s per sqrt(Hz)."""
    bias_sigma: float = 0.01 * DEG
    scale_sigma: float = 0.003


KOBUKI_GYRO = GyroParams()


@dataclass(frozen=True)
class Gyro:
    """One gyro's calibration residuals, fixed for a run."""

    bias: float = 0.0
    scale: float = 0.0
    params: GyroParams = KOBUKI_GYRO

    @classmethod
    def draw(cls, rng: np.random.Generator, params: GyroParams = KOBUKI_GYRO) -> "Gyro":
        """A gyro as it comes out of the factory and the start-up calibration."""
        return cls(params.bias_sigma * float(rng.standard_normal()),
                   params.scale_sigma * float(rng.standard_normal()), params)


def measure(gyro: Gyro, true_rate: float, dt: float, rng: np.random.Generator | None) -> float:
    """The yaw rate (rad/s) the gyro reports for ``true_rate`` over a sample of ``dt`` s (``rng`` None: no noise)."""
    p = gyro.params
    rate = (1.0 + gyro.scale) * true_rate + gyro.bias
    if rng is not None and p.noise_density > 0.0:
        rate += p.noise_density / math.sqrt(dt) * float(rng.standard_normal())
    rate = max(-p.range, min(p.range, rate))
    return round(rate / p.resolution) * p.resolution if p.resolution > 0.0 else rate
