"""Ground truth: where a robot's markers are in a camera's optical frame (what ``perception`` should find).

Moved unchanged from ``robot_bridge/sim/camera.py`` (issue 23); the package's ``__init__`` says how the
camera works.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from perception import markers
from robot_bridge.sim.camera.scene import CameraRig, Pose, Scene

FAR_MARGIN_M = 0.5
"""Beyond the depth sensor's range by this much (15 noise sigmas there), a cylinder reads no depth at all."""
EDGE_MARGIN_M = 0.05
"""Sideways slack beyond a cylinder's radius at the image's edges."""


@dataclass(frozen=True)
class TrueView:
    """Where a robot's markers are in a camera's optical frame, per the ``Detection`` definitions."""

    angle_deg: float        # bearing of the midpoint of the two axes, degrees(atan2(x, z)), + right
    depth_m: float          # mean optical-axis depth of the two axes
    yaw_deg: float          # degrees(atan2(hx, hz)), h = front - rear: 0 = facing away, 90 = moving right
    x_m: float
    z_m: float
    front_xz: tuple[float, float]
    rear_xz: tuple[float, float]
    front_u: float          # pixel column of each axis
    rear_u: float


def to_camera(rig: CameraRig, camera_pose: Pose, x: float, y: float) -> tuple[float, float]:
    """World point (x, y) -> optical-frame (x right, z forward) of a camera at ``camera_pose``."""
    cx, cy, yaw = camera_pose
    dx, dy = x - cx, y - cy
    c, s = math.cos(yaw), math.sin(yaw)
    return (-(-s * dx + c * dy), c * dx + s * dy)


def true_view(rig: CameraRig, camera_pose: Pose, robot: Pose) -> TrueView:
    """Ground truth for ``robot`` seen by the camera at ``camera_pose`` (pose of the optical centre)."""
    rx, ry, ryaw = robot
    c, s = math.cos(ryaw), math.sin(ryaw)
    fx_, fz_ = to_camera(rig, camera_pose, rx + c * markers.FRONT_OFFSET_M, ry + s * markers.FRONT_OFFSET_M)
    bx_, bz_ = to_camera(rig, camera_pose, rx + c * markers.REAR_OFFSET_M, ry + s * markers.REAR_OFFSET_M)
    mx, mz = (fx_ + bx_) / 2, (fz_ + bz_) / 2
    cam = rig.camera
    return TrueView(
        angle_deg=math.degrees(math.atan2(mx, mz)), depth_m=mz,
        yaw_deg=math.degrees(math.atan2(fx_ - bx_, fz_ - bz_)), x_m=mx, z_m=mz,
        front_xz=(fx_, fz_), rear_xz=(bx_, bz_),
        front_u=cam.fx * fx_ / fz_ + cam.cx if fz_ > 0 else math.nan,
        rear_u=cam.fx * bx_ / bz_ + cam.cx if bz_ > 0 else math.nan)


def may_show_robots(rig: CameraRig, camera_pose: Pose, robots: "tuple[Pose, ...] | list[Pose]", scene: Scene) -> bool:
    """Whether a marker cylinder of any of ``robots`` may be in the view: in front of the camera, within the
    image's columns and within the depth sensor's range (with margins). False means the detector cannot
    find a robot in the frame (a pair needs a cylinder with depth readings, ``perception.detect``), so a
    detector need not render it: in a team spread over an arena most frames show nobody."""
    cam = rig.camera
    tan_half = max(cam.cx, cam.width - cam.cx) / cam.fx
    far = scene.depth.max_m + FAR_MARGIN_M
    reach = markers.CYLINDER_RADIUS_M + EDGE_MARGIN_M
    for rx, ry, ryaw in robots:
        c, s = math.cos(ryaw), math.sin(ryaw)
        for offset in (markers.FRONT_OFFSET_M, markers.REAR_OFFSET_M):
            x, z = to_camera(rig, camera_pose, rx + c * offset, ry + s * offset)
            if -reach < z < far and abs(x) <= max(z, 0.0) * tan_half + 2 * reach:
                return True
    return False
