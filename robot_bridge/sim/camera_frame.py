"""``CameraFrame``: one rendered image, the type the world, its cameras and the bridges share.

Moved unchanged from ``robot_bridge/sim/world.py`` (issue 23), so that the camera (which hands out frames)
does not import the world (which asks it for them); ``world.CameraFrame`` still names it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CameraFrame:
    """One rendered image: RGB (H x W x 3 uint8) and registered depth (H x W float32 m, 0 = no reading)."""

    robot: str
    time: float
    pose: tuple[float, float, float]
    """Pose of the optical centre in the world (x, y, yaw rad) when the frame was taken."""
    camera: object
    """The ``perception.camera.CameraModel`` (intrinsics) of the frame."""
    rgb: np.ndarray
    depth: np.ndarray
