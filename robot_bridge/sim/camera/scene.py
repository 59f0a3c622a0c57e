"""What a camera looks at: its rig, the walls, props and robots' looks, the depth sensor's figures, the scene.

Moved unchanged from ``robot_bridge/sim/camera.py`` (issue 23); the package's ``__init__`` says how the
camera works.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from perception import markers
from perception.camera import CameraModel


Pose = tuple[float, float, float]      # x, y, yaw (radians) in the world frame


RGB = tuple[int, int, int]


_NEAR_M = 0.05          # objects closer than this to the camera plane are not drawn


_FAR = np.float32(np.inf)


@dataclass(frozen=True)
class CameraRig:
    """Where a camera sits on its robot: height of the optical centre and offset from the robot centre."""

    camera: CameraModel = field(default_factory=CameraModel.kinect)
    height_m: float = 0.30
    mount_x_m: float = 0.10
    mount_y_m: float = 0.0

    def pose_of(self, robot_pose: Pose) -> Pose:
        """World pose (x, y, yaw) of the camera's optical centre on a robot at ``robot_pose``."""
        x, y, yaw = robot_pose
        c, s = math.cos(yaw), math.sin(yaw)
        return (x + c * self.mount_x_m - s * self.mount_y_m, y + s * self.mount_x_m + c * self.mount_y_m, yaw)


@dataclass(frozen=True)
class Wall:
    """A vertical wall along the segment (x0, y0)-(x1, y1), from the floor to ``height_m``."""

    x0: float
    y0: float
    x1: float
    y1: float
    height_m: float = 2.5
    rgb: RGB = (205, 200, 188)


@dataclass(frozen=True)
class CylinderProp:
    """A vertical cylinder standing in the world (distractor, occluder, or a marker look-alike)."""

    x: float
    y: float
    radius_m: float
    bottom_m: float
    top_m: float
    rgb: RGB


@dataclass(frozen=True)
class BoxProp:
    """A vertical box (footprint ``length_m`` along its yaw, ``width_m`` across)."""

    x: float
    y: float
    yaw: float
    length_m: float
    width_m: float
    bottom_m: float
    top_m: float
    rgb: RGB


@dataclass(frozen=True)
class RobotLook:
    """How a robot appears: a dark body topped by the front and rear marker cylinders."""

    body_radius_m: float = 0.177
    body_top_m: float = markers.CYLINDER_BOTTOM_M
    body_rgb: RGB = (58, 58, 62)
    front_rgb: RGB = markers.MARKER_RGB[markers.FRONT_COLOUR]
    rear_rgb: RGB = markers.MARKER_RGB[markers.REAR_COLOUR]


@dataclass(frozen=True)
class DepthSensor:
    """Kinect v1 depth behaviour: disparity noise (so depth noise grows as z^2), 1/8 px disparity steps."""

    min_m: float = 0.8
    max_m: float = 4.5
    disparity_noise_px: float = 0.07        # ~ Nguyen et al. 2012: sigma_z = 0.0012 + 0.0019 (z - 0.4)^2
    noise_blur_px: float = 1.0              # spatial correlation of the noise (block matching)
    focal_baseline_px_m: float = 580.0 * 0.075
    subpixel: int = 8
    dropout: float = 0.02                   # fraction of random holes
    shadows: bool = True                    # projector shadow left of foreground objects
    registration_px: int = 1                # depth-to-colour registration error (columns)


@dataclass(frozen=True)
class Scene:
    """Everything static a camera sees besides the robots, plus the lighting and sensor settings."""

    walls: tuple[Wall, ...] = ()
    props: tuple[CylinderProp | BoxProp, ...] = ()
    gain: float = 1.0                       # illumination: multiplies every colour (saturating)
    floor_rgb: RGB = (150, 140, 128)
    backdrop_rgb: RGB = (120, 122, 128)     # what is seen where there is no wall (depth: no reading)
    rgb_noise: float = 2.5                  # sensor noise, grey levels (sigma)
    depth: DepthSensor = field(default_factory=DepthSensor)
    robot_look: RobotLook = field(default_factory=RobotLook)


def _rgb8(rgb) -> np.ndarray:
    """RGB values (..., 3), any real type, -> uint8 (rounded, saturating)."""
    return np.clip(np.rint(np.asarray(rgb, np.float64)), 0, 255).astype(np.uint8)
