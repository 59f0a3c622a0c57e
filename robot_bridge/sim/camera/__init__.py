"""A Kinect-like RGB-D camera for the simulator: real pixel arrays for ``perception/`` to process.

World frame per REP 103: x forward, y left, z up, yaw counter-clockwise. The camera is level (no
pitch or roll), which is what makes rendering cheap: the floor's depth depends only on the image row,
a wall's only on the column, and every object (robot bodies, the marker cylinders, props) is a
vertical prism whose silhouette is a band of columns. Output follows the Kinect's ROS driver: an
``rgb8`` image (H x W x 3 uint8, RGB order) and a registered depth image (H x W float32 metres along
the optical axis, 0 = no reading) with depth-dependent noise, disparity quantisation, dropouts,
projector shadows and out-of-range holes. Noise comes from banks drawn once per camera, so a frame
costs a few milliseconds instead of hundreds of thousands of fresh Gaussian draws.

Where a frame's time goes, and what keeps it short: a dozen whole-image passes (background, colour
noise, the depth measurement), each an OpenCV call or a numpy loop on uint8/float32; the z-buffer
holds disparity, the unit the sensor measures in. Per object only its band of rows and columns is
touched, the cylinders' silhouettes and rows computed for all at once. Rows below every wall and
object are bare floor, taken from noisy floor banks at a random column; rows above everything within
the depth range (widened by the largest noise in the bank) read 0 whatever the noise, and are not
measured. A camera that stands still keeps its static layers (floor, walls, props) and only draws the
robots.

The world hands out ``DeferredFrame``s: a snapshot of the scene and a noise seed, rendered the first
time someone reads the pixels, so a camera nobody looks at costs nothing; ``render_all`` renders the
frames due at one step side by side on the cores. ``frames_rendered`` counts the frames actually
made. Pixels depend only on the scene and the seed, never on caches, threads or when they are read.

Stages, one module each: ``scene`` (what a camera looks at), ``truth`` (where markers really are),
``background`` (floor and walls), ``objects`` (the prisms, z-buffered), ``depth`` (the sensor's
measurement and noise), ``renderer`` (per-camera banks and caches), ``pipeline`` (one frame, stage after
stage), ``frames`` (deferred frames, and the frames of one step rendered side by side).
"""
from __future__ import annotations

from robot_bridge.sim.camera_frame import CameraFrame
from robot_bridge.sim.camera.frames import DeferredFrame, _Pace, deferred_frame, render_all, render_threads
from robot_bridge.sim.camera.pipeline import MarkerPixels, _render, frames_rendered, render, render_with_pixels
from robot_bridge.sim.camera.renderer import _renderer
from robot_bridge.sim.camera.scene import (BoxProp, CameraRig, CylinderProp, DepthSensor, Pose, RGB, RobotLook, Scene,
                                           Wall)
from robot_bridge.sim.camera.truth import TrueView, may_show_robots, to_camera, true_view

__all__ = ["CameraFrame", "BoxProp", "CameraRig", "CylinderProp", "DepthSensor", "Pose", "RGB", "RobotLook", "Scene",
           "Wall", "TrueView", "may_show_robots", "to_camera", "true_view", "MarkerPixels", "frames_rendered", "render",
           "render_with_pixels", "DeferredFrame", "deferred_frame", "render_all", "render_threads"]
