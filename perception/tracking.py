"""Smooth detections over frames; call a robot lost only after several missed frames.

The seed paper's Helper turned away from Faulty after one bad frame (its run 6). ``Tracker`` keeps the
last estimate through up to ``lost_after - 1`` misses, smooths angle, depth and heading (heading on
the circle), and does not let one outlying frame drag the estimate: a jump beyond the gates is
accepted only when the next frame confirms it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from perception.detect import Detection, DetectionResult


@dataclass(frozen=True)
class TrackState:
    """What the Helper believes about the tracked robot after a frame."""

    visible: bool               # detected in this frame (and accepted)
    lost: bool                  # never seen, or missed ``lost_after`` frames in a row
    angle_deg: float | None     # smoothed, camera frame (+ right)
    depth_m: float | None
    yaw_deg: float | None
    missed: int                 # consecutive frames without an accepted detection
    frames: int                 # frames seen so far


def _wrap(deg: float) -> float:
    return (deg + 180.0) % 360.0 - 180.0


class Tracker:
    """Exponential smoothing with gates. ``alpha`` weights the new frame (1 = no smoothing)."""

    def __init__(self, lost_after: int = 5, alpha: float = 0.5, gate_angle_deg: float = 8.0,
                 gate_depth_m: float = 0.4, gate_yaw_deg: float = 60.0) -> None:
        if lost_after < 1:
            raise ValueError(f"lost_after must be >= 1, got {lost_after}")
        if not 0 < alpha <= 1:
            raise ValueError(f"alpha must be in (0, 1], got {alpha}")
        self.lost_after, self.alpha = lost_after, alpha
        self.gates = (gate_angle_deg, gate_depth_m, gate_yaw_deg)
        self.reset()

    def reset(self) -> None:
        self._est: tuple[float, float, float] | None = None
        self._pending: Detection | None = None
        self._missed = 0
        self._frames = 0

    def update(self, result: DetectionResult | Detection | None) -> TrackState:
        """Feed one frame's result (a ``DetectionResult``, a ``Detection`` or None for a miss)."""
        self._frames += 1
        det = result.detection if isinstance(result, DetectionResult) else result
        accepted = False
        if det is not None:
            if self._est is None or self._within_gates(det):
                self._blend(det)
                accepted = True
                self._pending = None
            elif self._pending is not None and self._close(self._pending, det):
                self._est = (det.angle_deg, det.depth_m, det.yaw_deg)   # confirmed jump: re-acquire
                accepted = True
                self._pending = None
            else:
                self._pending = det
        else:
            self._pending = None
        self._missed = 0 if accepted else self._missed + 1
        if self._missed >= self.lost_after:
            self._est = None                # lost: the next detection starts a fresh track
        lost = self._est is None
        est = self._est
        return TrackState(visible=accepted, lost=lost, angle_deg=est[0] if est else None,
                          depth_m=est[1] if est else None, yaw_deg=est[2] if est else None,
                          missed=self._missed, frames=self._frames)

    def _within_gates(self, det: Detection) -> bool:
        a, d, y = self._est
        ga, gd, gy = self.gates
        # gates widen with every miss: the robot may have moved while unseen
        grow = 1 + self._missed
        return (abs(det.angle_deg - a) <= ga * grow and abs(det.depth_m - d) <= gd * grow
                and abs(_wrap(det.yaw_deg - y)) <= gy * grow)

    def _close(self, a: Detection, b: Detection) -> bool:
        ga, gd, gy = self.gates
        return (abs(a.angle_deg - b.angle_deg) <= ga and abs(a.depth_m - b.depth_m) <= gd
                and abs(_wrap(a.yaw_deg - b.yaw_deg)) <= gy)

    def _blend(self, det: Detection) -> None:
        if self._est is None:
            self._est = (det.angle_deg, det.depth_m, det.yaw_deg)
            return
        k = self.alpha
        a, d, y = self._est
        # heading on the circle: blend the unit vectors
        sy = (1 - k) * math.sin(math.radians(y)) + k * math.sin(math.radians(det.yaw_deg))
        cy = (1 - k) * math.cos(math.radians(y)) + k * math.cos(math.radians(det.yaw_deg))
        self._est = (a + k * (det.angle_deg - a), d + k * (det.depth_m - d), math.degrees(math.atan2(sy, cy)))
