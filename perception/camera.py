"""Pinhole camera model in the ROS optical frame: x right, y DOWN, z forward (REP 103 ``_optical``).

Pixel (u, v) is the centre of column u, row v; ``cx = (width - 1) / 2`` puts the optical axis between
the two middle pixels, as ROS camera_info does for an ideal camera.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CameraModel:
    """Intrinsics of an undistorted camera (focal lengths and principal point in pixels)."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    def __post_init__(self) -> None:
        if self.width <= 0 or self.height <= 0 or self.fx <= 0 or self.fy <= 0:
            raise ValueError(f"camera needs positive size and focal lengths, got {self}")

    @classmethod
    def from_fov(cls, hfov_deg: float = 57.0, vfov_deg: float = 43.0,
                 width: int = 640, height: int = 480) -> "CameraModel":
        """Intrinsics whose field of view is exactly ``hfov x vfov`` degrees (edge to edge of the image)."""
        if not (0 < hfov_deg < 180 and 0 < vfov_deg < 180):
            raise ValueError(f"field of view must be in (0, 180) degrees, got {hfov_deg} x {vfov_deg}")
        fx = (width / 2) / math.tan(math.radians(hfov_deg) / 2)
        fy = (height / 2) / math.tan(math.radians(vfov_deg) / 2)
        return cls(width, height, fx, fy, (width - 1) / 2, (height - 1) / 2)

    @classmethod
    def kinect(cls) -> "CameraModel":
        """Kinect v1 colour camera: 640x480, 57 x 43 degrees."""
        return cls.from_fov(57.0, 43.0, 640, 480)

    @property
    def hfov_deg(self) -> float:
        return math.degrees(2 * math.atan((self.width / 2) / self.fx))

    @property
    def vfov_deg(self) -> float:
        return math.degrees(2 * math.atan((self.height / 2) / self.fy))

    def project(self, points_xyz: np.ndarray) -> np.ndarray:
        """(..., 3) camera-frame points -> (..., 2) pixel coordinates (u, v); z must be > 0."""
        p = np.asarray(points_xyz, dtype=np.float64)
        z = p[..., 2]
        return np.stack((self.fx * p[..., 0] / z + self.cx, self.fy * p[..., 1] / z + self.cy), axis=-1)

    def backproject(self, u, v, depth) -> np.ndarray:
        """Pixel coordinates and optical-axis depth z (metres) -> (..., 3) camera-frame points."""
        z = np.asarray(depth, dtype=np.float64)
        x = (np.asarray(u, dtype=np.float64) - self.cx) * z / self.fx
        y = (np.asarray(v, dtype=np.float64) - self.cy) * z / self.fy
        return np.stack(np.broadcast_arrays(x, y, z), axis=-1)

    def bearing_deg(self, u: float) -> float:
        """Horizontal angle of pixel column u, positive to the right: ``degrees(atan2(x, z))``."""
        return math.degrees(math.atan((u - self.cx) / self.fx))
