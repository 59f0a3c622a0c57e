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
"""
from __future__ import annotations

import math
import os
import threading
from collections import OrderedDict, deque
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import lru_cache
from time import perf_counter
from typing import Sequence

import numpy as np

from perception import markers
from perception.camera import CameraModel
from robot_bridge.sim import zbuffer
from robot_bridge.sim.world import CameraFrame

Pose = tuple[float, float, float]      # x, y, yaw (radians) in the world frame
RGB = tuple[int, int, int]

_NEAR_M = 0.05          # objects closer than this to the camera plane are not drawn
_ZBUFFER = zbuffer.load()   # the compiled cylinder loop, or None: numpy draws (same pixels)
_FAR = np.float32(np.inf)


# --------------------------------------------------------------------------------------------- scene
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


# ----------------------------------------------------------------------------------------- truth
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


# ---------------------------------------------------------------------------------------- render
@dataclass(frozen=True)
class MarkerPixels:
    """Pixel counts of one robot's markers: as rendered (``*_visible``) and if nothing hid them (``*_full``)."""

    front_visible: int
    front_full: int             # counted inside the image only
    rear_visible: int
    rear_full: int
    front_in_frame: bool = True     # the cylinder's axis projects inside the image
    rear_in_frame: bool = True

    def both_visible(self, min_fraction: float = 0.4, min_px: int = 30) -> bool:
        """Both axes in the image, and both cylinders show at least ``min_fraction`` of their
        silhouette and ``min_px`` pixels."""
        return self.front_in_frame and self.rear_in_frame and all(
            vis >= min_px and vis >= min_fraction * full
            for vis, full in ((self.front_visible, self.front_full), (self.rear_visible, self.rear_full)))


@dataclass
class _Prism:
    footprint: str                  # "circle" or "box"
    cam_xz: tuple[float, float]     # centre in the optical frame
    radius: float                   # circle
    half: tuple[float, float]       # box half sizes along its axes
    axis: tuple[float, float]       # box length axis in the optical frame (x, z)
    bottom: float
    top: float
    rgb: RGB
    label: int                      # 0 = not tracked, else an id for MarkerPixels


class _Renderer:
    """Per-camera constants, noise banks and scratch buffers; one instance per rig (cached).

    Banks are drawn once; a frame picks a random offset into them, so per-frame noise costs a slice
    instead of fresh Gaussian draws. Scratch buffers are per thread (worlds may render in parallel).
    """

    def __init__(self, rig: CameraRig, sensor: DepthSensor, seed: int = 12345) -> None:
        import cv2

        cam = rig.camera
        self.rig, self.cam, self.sensor = rig, cam, sensor
        h, w = cam.height, cam.width
        self.tan_u = ((np.arange(w) - cam.cx) / cam.fx).astype(np.float32)          # x / z per column
        self.tan_u64 = (np.arange(w) - cam.cx) / cam.fx
        self.k_v = ((np.arange(h) - cam.cy) / cam.fy).astype(np.float32)            # (down) / z per row
        self.inv_k32 = (1.0 / ((np.arange(h) - cam.cy) / cam.fy)).astype(np.float32)  # cy is never a row
        with np.errstate(divide="ignore"):
            floor = np.where(self.k_v > 0, rig.height_m / self.k_v, np.inf)
        self.floor_z = floor.astype(np.float32)[:, None]
        # the z-buffer holds disparity in 1/subpixel steps (fb / z, 0 = nothing), what the sensor measures
        self.fb32 = np.float32(sensor.focal_baseline_px_m * sensor.subpixel)
        self.floor_d_image = np.ascontiguousarray(np.broadcast_to(self.fb32 / self.floor_z, (h, w)))
        self.k_v32 = self.k_v.astype(np.float32)[:, None]
        self.rows = np.arange(h, dtype=np.int16)[:, None]
        # floor shading per row: a little darker far away
        self.floor_shade = np.clip(0.72 + 0.28 * np.exp(-np.nan_to_num(floor, posinf=50) / 6), 0, 1)[:, None]
        self.half_fov = math.atan((max(cam.cx, w - 1 - cam.cx) + 1) / cam.fx)
        rng = np.random.default_rng(seed)
        extra = 64
        white = rng.standard_normal((h + extra, w + extra)).astype(np.float32)
        if sensor.noise_blur_px > 0:
            white = cv2.GaussianBlur(white, (0, 0), sensor.noise_blur_px)
            white /= white.std()
        bank = white * np.float32(sensor.disparity_noise_px * sensor.subpixel)
        # dropouts ride in the same bank: a hugely negative disparity is an invalid reading
        bank[rng.random((h + extra, w + extra)) < sensor.dropout] = np.float32(-1e9)
        self.disparity_bank = bank.ravel()          # a frame takes h * w values from a random offset
        # only true disparities within the largest noise of the bank (plus a step) of the range can read
        # anything; nearer or farther the reading is 0 whatever the noise (``_depth_noise`` skips them)
        readings = bank[bank > -1e8]
        reach = (float(np.abs(readings).max()) if readings.size else 0.0) + 1.0
        d_lo = float(self.fb32) / sensor.max_m - reach
        d_hi = float(self.fb32) / (sensor.min_m - 1e-6) + reach
        self.z_readable = (float(self.fb32) / d_hi, float(self.fb32) / d_lo if d_lo > 0 else math.inf)
        floor_d = self.floor_d_image[:, 0]
        self.first_readable_floor_row = int(np.argmax(floor_d >= d_lo)) if (floor_d >= d_lo).any() else h
        colour = rng.normal(0.0, 1.0, (h + extra, w, 3)).astype(np.float32)
        self.colour_bank_unit = colour
        self._colour_cache: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        self._floor_cache: dict[tuple, np.ndarray] = {}
        self.first_floor_row = int(np.argmax(self.k_v > 0))
        # below the lowest wall and object a frame is bare floor: its noisy pixels come from banks
        # (the floor is the same along a row, so a random column offset gives fresh noise)
        self.floor_banks = w >= h               # the colour bank re-read as rows of w + extra pixels
        self._floor_depth_bank: np.ndarray | None = None
        self._floor_colour_cache: dict[tuple, np.ndarray] = {}
        self._height_cache: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}
        self._cap_blocks: dict[tuple, np.ndarray] = {}
        self._static: OrderedDict[tuple, tuple] = OrderedDict()     # static layers of cameras standing still
        self._poses_seen: OrderedDict[tuple, None] = OrderedDict()
        self._static_lock = threading.Lock()
        self._local = threading.local()
        self.extra = extra

    def colour_noise(self, sigma: float) -> tuple[np.ndarray, np.ndarray]:
        """Positive and negative parts of the colour noise bank as uint8 (for saturating add/subtract)."""
        if sigma not in self._colour_cache:
            n = np.rint(self.colour_bank_unit * sigma)
            self._colour_cache[sigma] = (np.clip(n, 0, 255).astype(np.uint8), np.clip(-n, 0, 255).astype(np.uint8))
        return self._colour_cache[sigma]

    def floor_image(self, floor_rgb: RGB, backdrop_rgb: RGB, gain: float) -> np.ndarray:
        """Colours of the floor (shaded per row) below the horizon and the backdrop above it."""
        import cv2

        key = (floor_rgb, backdrop_rgb, gain)
        img = self._floor_cache.get(key)
        if img is None:
            floor_row = np.where(self.k_v > 0, 1.0, 0.0)[:, None]
            row_rgb = floor_row * np.asarray(floor_rgb) * self.floor_shade + (1 - floor_row) * np.asarray(backdrop_rgb)
            # rows of 3-byte pixels copy slowly (numpy and cv2.repeat alike): broadcast 4-byte RGBA, then drop A
            rgba = np.ascontiguousarray(np.broadcast_to(
                np.concatenate([_rgb8(row_rgb * gain), np.zeros((len(row_rgb), 1), np.uint8)], axis=1)
                .view(np.uint32), (self.cam.height, self.cam.width)))
            img = cv2.cvtColor(rgba.view(np.uint8).reshape(self.cam.height, self.cam.width, 4), cv2.COLOR_RGBA2RGB)
            if len(self._floor_cache) >= 8:           # scenes with ever new lighting must not pile up
                self._floor_cache.clear()
            self._floor_cache[key] = img
        return img

    def floor_depth_bank(self) -> np.ndarray:
        """Depth readings (h x (w + extra) float32) of the bare floor, noise, holes and range included."""
        bank = self._floor_depth_bank
        if bank is None:
            h, w, e = self.cam.height, self.cam.width, self.extra
            noise = self.disparity_bank.reshape(h + e, w + e)[:h]
            bank = _measure(self, np.broadcast_to(self.floor_d_image[:, :1], noise.shape), noise,
                            np.empty(noise.shape, np.float32))
            self._floor_depth_bank = bank
        return bank

    def floor_colour_bank(self, floor_rgb: RGB, gain: float, sigma: float) -> np.ndarray:
        """Noisy colours of the floor rows (from ``first_floor_row`` down) ``extra`` pixels wider than the image."""
        import cv2

        key = (floor_rgb, gain, sigma)
        bank = self._floor_colour_cache.get(key)
        if bank is None:
            h, w, e, f = self.cam.height, self.cam.width, self.extra, self.first_floor_row
            rgb = _rgb8(np.asarray(floor_rgb) * self.floor_shade[f:] * gain)
            # rows of 3-byte pixels copy slowly: broadcast 4-byte RGBA, then drop A
            rgba = np.ascontiguousarray(np.broadcast_to(
                np.concatenate([rgb, np.zeros((h - f, 1), np.uint8)], axis=1).view(np.uint32), (h - f, w + e)))
            bank = cv2.cvtColor(rgba.view(np.uint8).reshape(h - f, w + e, 4), cv2.COLOR_RGBA2RGB)
            pos, neg = self.colour_noise(sigma)
            size = h * (w + e) * 3
            cv2.add(bank, pos.reshape(-1)[:size].reshape(h, w + e, 3)[f:], dst=bank)
            cv2.subtract(bank, neg.reshape(-1)[:size].reshape(h, w + e, 3)[f:], dst=bank)
            if len(self._floor_colour_cache) >= 8:     # scenes with ever new lighting must not pile up
                self._floor_colour_cache.clear()
            self._floor_colour_cache[key] = bank
        return bank

    def cap_block(self, rgb: RGB, factor: float, rows: int, cols: int) -> np.ndarray:
        """A ``rows`` x ``cols`` block of one cap colour to copy from through a mask (kept per colour,
        grown as needed; read-only)."""
        key = (rgb, factor)
        block = self._cap_blocks.get(key)
        if block is None or block.shape[0] < rows or block.shape[1] < cols:
            shape = (rows, cols) if block is None else (max(rows, block.shape[0]), max(cols, block.shape[1]))
            block = np.empty(shape + (3,), np.uint8)
            block[:] = _cap_colour(rgb, factor)
            if len(self._cap_blocks) >= 16:                # scenes with ever new lighting must not pile up
                self._cap_blocks.clear()
            self._cap_blocks[key] = block
        return block[:rows, :cols]

    def height_limits(self, bottom: float, top: float) -> tuple[np.ndarray, np.ndarray]:
        """Per row (h x 1 float32), the depths between which a ray is within ``bottom..top`` in height."""
        key = (bottom, top)
        limits = self._height_cache.get(key)
        if limits is None:
            hc = self.rig.height_m
            qa = self.inv_k32 * np.float32(hc - top)       # k > 0: qa <= z <= qb; k < 0: reversed
            qb = self.inv_k32 * np.float32(hc - bottom)
            limits = (np.minimum(qa, qb)[:, None], np.maximum(qa, qb)[:, None])
            if len(self._height_cache) >= 64:              # scenes with ever new props must not pile up
                self._height_cache.clear()
            self._height_cache[key] = limits
        return limits

    def static_layers(self, pose: Pose, scene: Scene, canvas: np.ndarray, disparity: np.ndarray
                      ) -> tuple[list[tuple], int, int, bool]:
        """Floor and walls, and maybe the props, seen from ``pose`` into ``canvas`` and ``disparity``;
        what ``_static_layers`` returns, and whether the props are drawn.

        A pose asked for a second time is a camera standing still: its layers, props included, are kept
        (a few dozen poses, least recently used dropped) and later frames copy them instead of drawing
        them. A moving camera never pays for the copies, and its props are left to be drawn with the
        robots (one batch of cylinders instead of two).
        """
        key = (pose, id(scene))
        with self._static_lock:
            kept = self._static.get(key)
            if kept is not None and kept[0] is scene:
                self._static.move_to_end(key)
            else:
                kept = None
                again = key in self._poses_seen
                self._poses_seen[key] = None
                self._poses_seen.move_to_end(key)
                if len(self._poses_seen) > 256:
                    self._poses_seen.popitem(last=False)
        if kept is not None:
            np.copyto(canvas, kept[1])
            np.copyto(disparity, kept[2])
            return list(kept[3]), kept[4], kept[5], True
        shadows, floor_from, wall_readable = _static_layers(self, pose, scene, canvas, disparity, props=again)
        if again:
            with self._static_lock:
                self._static[key] = (scene, canvas.copy(), disparity.copy(), tuple(shadows), floor_from,
                                     wall_readable)
                if len(self._static) > 32:
                    self._static.popitem(last=False)
        return shadows, floor_from, wall_readable, again

    def scratch(self) -> tuple[np.ndarray, np.ndarray]:
        """This thread's colour and depth buffers (re-used frame after frame)."""
        bufs = getattr(self._local, "bufs", None)
        if bufs is None:
            h, w = self.cam.height, self.cam.width
            bufs = self._local.bufs = (np.empty((h, w, 3), np.uint8), np.empty((h, w), np.float32))
        return bufs


@lru_cache(maxsize=32)
def _renderer(rig: CameraRig, sensor: DepthSensor) -> _Renderer:
    return _Renderer(rig, sensor)


def _rgb8(rgb) -> np.ndarray:
    """RGB values (..., 3), any real type, -> uint8 (rounded, saturating)."""
    return np.clip(np.rint(np.asarray(rgb, np.float64)), 0, 255).astype(np.uint8)


def render(rig: CameraRig, camera_pose: Pose, robots: Sequence[Pose], scene: Scene,
           rng: np.random.Generator | None = None) -> tuple[np.ndarray, np.ndarray]:
    """One RGB-D frame from a camera whose optical centre is at ``camera_pose`` (see ``CameraRig.pose_of``).

    Returns ``(rgb, depth)``: H x W x 3 uint8 in RGB order, H x W float32 metres (0 = no reading).
    """
    rgb, depth, _ = _render(rig, camera_pose, robots, scene, rng, count=False)
    return rgb, depth


def render_with_pixels(rig: CameraRig, camera_pose: Pose, robots: Sequence[Pose], scene: Scene,
                       rng: np.random.Generator | None = None
                       ) -> tuple[np.ndarray, np.ndarray, list[MarkerPixels]]:
    """Like ``render``, plus each robot's visible and unoccluded marker pixel counts (ground truth)."""
    return _render(rig, camera_pose, robots, scene, rng, count=True)


_frames = [0]
_frames_lock = threading.Lock()


def frames_rendered() -> int:
    """How many frames this process has rendered so far (for benchmarks: frames made, not frames due)."""
    return _frames[0]


class DeferredFrame(CameraFrame):
    """A ``CameraFrame`` whose pixels are rendered the first time ``rgb`` or ``depth`` is read.

    The scene (every robot's pose, the time) is fixed when the frame is taken, and the sensor noise
    comes from a seed drawn then, so the pixels are the same whenever, and whether, they are read;
    a 10 Hz camera whose frames nobody looks at costs a pose snapshot per frame, not a render.
    """

    def __init__(self, robot: str, time: float, pose: Pose, rig: CameraRig, robots: Sequence[Pose],
                 scene: Scene, seed: int) -> None:
        for name, value in (("robot", robot), ("time", time), ("pose", pose), ("camera", rig.camera),
                            ("_job", (rig, pose, tuple(robots), scene, seed)), ("_pixels", None),
                            ("_lock", threading.Lock())):
            object.__setattr__(self, name, value)

    def _render(self) -> tuple[np.ndarray, np.ndarray]:
        pixels = self._pixels
        if pixels is None:
            with self._lock:                # listeners in several threads: render once
                pixels = self._pixels
                if pixels is None:
                    rig, pose, robots, scene, seed = self._job
                    pixels = render(rig, pose, robots, scene, np.random.default_rng(seed))
                    object.__setattr__(self, "_pixels", pixels)
        return pixels

    @property
    def rendered(self) -> bool:
        return self._pixels is not None

    @property
    def job(self) -> tuple[CameraRig, Pose, tuple[Pose, ...], Scene, int]:
        """What the pixels depend on: rig, camera pose, the robots' poses, scene and noise seed."""
        return self._job

    def deliver(self, rgb: np.ndarray, depth: np.ndarray) -> None:
        """Take pixels rendered elsewhere (a render worker) from this frame's ``job``; counted as rendered."""
        with self._lock:
            if self._pixels is None:
                object.__setattr__(self, "_pixels", (rgb, depth))
                with _frames_lock:
                    _frames[0] += 1

    @property
    def rgb(self) -> np.ndarray:            # type: ignore[override]
        return self._render()[0]

    @property
    def depth(self) -> np.ndarray:          # type: ignore[override]
        return self._render()[1]

    def __reduce__(self):
        return (CameraFrame, (self.robot, self.time, self.pose, self.camera, self.rgb, self.depth))


_pool: list = []
_pool_lock = threading.Lock()


def render_threads() -> int:
    """Threads that render frames side by side: one per core this process may use (at most 4)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:                  # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(cores, 4))


class _Pace:
    """Wall time per frame rendered one by one and side by side (moving averages), to use the faster.

    A second thread pays only when a core is free, and other programs may keep the cores busy. So
    both ways are timed, taking turns for the first ``TRIALS`` calls each (the first call of each,
    which warms caches up, not counted), then the faster one is used and the other is tried again
    every ``EXPLORE`` calls, as the load changes.
    """

    TRIALS = 4
    EXPLORE = 16

    def __init__(self) -> None:
        self.seconds: dict[bool, float | None] = {False: None, True: None}
        self.runs = {False: 0, True: 0}
        self.calls = 0

    def side_by_side(self) -> bool:
        self.calls += 1
        if min(self.runs.values()) < self.TRIALS:
            return self.runs[True] < self.runs[False]
        faster = self.seconds[True] < self.seconds[False]
        return not faster if self.calls % self.EXPLORE == 0 else faster

    def record(self, side_by_side: bool, seconds_per_frame: float) -> None:
        self.runs[side_by_side] += 1
        if self.runs[side_by_side] > 1:
            old = self.seconds[side_by_side]
            self.seconds[side_by_side] = seconds_per_frame if old is None else 0.7 * old + 0.3 * seconds_per_frame


_pace = _Pace()


def render_all(frames: Sequence[CameraFrame]) -> None:
    """Render the pixels of the deferred ``frames`` not rendered yet: shared with render worker
    processes once they have started (``render_processes``), else side by side in threads when that is
    faster (see ``_Pace``).

    Frames due at the same step (one per camera) are independent, and most of a frame's time is in
    OpenCV calls and whole-image numpy loops, which release the GIL. The calling thread renders too;
    pixels do not depend on which thread renders them (noise comes from the frame's seed).
    """
    todo = deque(f for f in frames if isinstance(f, DeferredFrame) and not f.rendered)
    count = len(todo)
    if count >= 2:
        from robot_bridge.sim.render_processes import shared_pool

        processes = shared_pool()
        if processes is not None and processes.ready():
            processes.render(todo)
            return
    helpers = min(count - 1, render_threads() - 1)

    def work() -> None:
        while True:
            try:
                frame = todo.popleft()
            except IndexError:
                return
            frame._render()

    if helpers <= 0:
        work()
        return
    side_by_side = _pace.side_by_side()
    started = perf_counter()
    if side_by_side:
        with _pool_lock:
            if not _pool:
                _pool.append(ThreadPoolExecutor(render_threads() - 1, thread_name_prefix="sim-camera"))
        futures = [_pool[0].submit(work) for _ in range(helpers)]
        work()
        for future in futures:
            future.result()
    else:
        work()
    _pace.record(side_by_side, (perf_counter() - started) / count)


def deferred_frame(robot: str, time: float, pose: Pose, rig: CameraRig, robots: Sequence[Pose], scene: Scene,
                   rng: np.random.Generator) -> DeferredFrame:
    """A frame of the camera at ``pose`` seeing ``robots`` now, rendered when its pixels are read."""
    return DeferredFrame(robot, time, pose, rig, robots, scene, int(rng.integers(0, 2 ** 63)))


def _render(rig: CameraRig, camera_pose: Pose, robots: Sequence[Pose], scene: Scene,
            rng: np.random.Generator | None, count: bool, out: tuple[np.ndarray, np.ndarray] | None = None
            ) -> tuple[np.ndarray, np.ndarray, list[MarkerPixels]]:
    """The frame's colour and depth images and, with ``count``, each robot's marker pixels. With ``out``
    (an H x W x 3 uint8 image and a flat float32 array of at least H * W + ``registration_px`` values,
    see ``render_processes.frame_views``) the pixels are written there (a render worker's shared memory) instead of
    into new arrays."""
    import cv2

    with _frames_lock:
        _frames[0] += 1
    rng = rng if rng is not None else np.random.default_rng()
    r = _renderer(rig, scene.depth)
    h, w = r.cam.height, r.cam.width
    gain = float(scene.gain)
    canvas, depth = r.scratch()

    # what does not move: floor, walls and (for a camera standing still) props
    shadows, floor_from, wall_readable, props_drawn = r.static_layers(camera_pose, scene, canvas, depth)
    # the robots (and the props if not drawn yet), with a depth test per pixel
    n_labels = 2 * len(robots)
    labels = np.zeros((h, w), np.int16) if count and n_labels else None
    full = np.zeros(n_labels + 1, np.int64)
    bands: dict[int, tuple[int, int, int, int]] = {}
    _draw(r, _prisms(r, camera_pose, robots, scene, count, props=not props_drawn), depth, canvas, labels,
          full if labels is not None else None, shadows,
          gain, bands)

    # rows from ``floor`` down see only floor (every object drawn left a shadow entry with its rows)
    floor = max([r.first_floor_row, floor_from] + [sh[2] for sh in shadows]) if r.floor_banks else h
    # rows above the first that can read anything (floor, walls or objects in range) read 0 whatever the noise
    far = r.z_readable[1]
    readable = min([r.first_readable_floor_row, wall_readable] + [sh[1] for sh in shadows if sh[4] <= far])
    image = np.empty((h, w, 3), np.uint8) if out is None else out[0]
    if scene.rgb_noise > 0:
        pos, neg = r.colour_noise(float(scene.rgb_noise))
        off = int(rng.integers(0, r.extra))
        top = image[:floor]
        cv2.add(canvas[:floor], pos[off:off + floor], dst=top)
        cv2.subtract(top, neg[off:off + floor], dst=top)
        if floor < h:
            col = int(rng.integers(0, r.extra))
            bank = r.floor_colour_bank(scene.floor_rgb, gain, float(scene.rgb_noise))
            image[floor:] = bank[floor - r.first_floor_row:, col:col + w]
    else:
        np.copyto(image, canvas)

    noisy = _depth_noise(r, depth, shadows, rng, min(readable, floor), floor, None if out is None else out[1])
    pixels: list[MarkerPixels] = []
    if count:
        visible = np.zeros(n_labels + 1, np.int64)
        for label, (v0, v1, u0, u1) in bands.items():
            visible[label] = int(np.count_nonzero(labels[v0:v1, u0:u1] == label))
        for i, robot in enumerate(robots):
            view = true_view(rig, camera_pose, robot)
            inside = [z > 0 and -0.5 <= u <= w - 0.5 for u, z in ((view.front_u, view.front_xz[1]),
                                                                   (view.rear_u, view.rear_xz[1]))]
            pixels.append(MarkerPixels(int(visible[1 + 2 * i]), int(full[1 + 2 * i]), int(visible[2 + 2 * i]),
                                       int(full[2 + 2 * i]), inside[0], inside[1]))
    return image, noisy, pixels


def _static_layers(r: _Renderer, pose: Pose, scene: Scene, canvas: np.ndarray, disparity: np.ndarray,
                   props: bool) -> tuple[list[tuple], int, int]:
    """Draw what does not move (floor, walls and, with ``props``, the props) into ``canvas`` and
    ``disparity``; returns the props' projector shadows, the row below which the walls leave only floor
    and the first row where a wall is near enough for the depth sensor to read it."""
    cam, hc, h = r.cam, r.rig.height_m, r.cam.height
    gain = float(scene.gain)
    # background: per column the backdrop above the wall's top, the wall, then the floor below the
    # wall-floor line; the wall is a column band, floor and backdrop depend on the row only
    wall_z, wall_idx = _wall_depths(r, pose, scene.walls)
    wall_top = _wall_table(tuple(scene.walls))[3][wall_idx]
    with np.errstate(invalid="ignore"):
        v_top = np.ceil(cam.cy + cam.fy * (hc - wall_top) / wall_z)
        v_bottom = np.floor(cam.cy + cam.fy * hc / wall_z) + 1
    no_wall = ~np.isfinite(wall_z)
    v_top = np.clip(np.where(no_wall, h, v_top), 0, h).astype(np.int16)
    v_bottom = np.clip(np.where(no_wall, h, v_bottom), 0, h).astype(np.int16)
    wall_rgb = _wall_colours(r, pose, scene.walls, wall_idx, wall_z)
    if gain != 1.0:
        wall_rgb = _rgb8(wall_rgb.astype(np.float64) * gain)
    wall_d = r.fb32 / wall_z.astype(np.float32)                    # disparity, see _Renderer
    _background(r, v_top, v_bottom, (wall_rgb, wall_d),
                (r.floor_image(scene.floor_rgb, scene.backdrop_rgb, gain), r.floor_d_image), (canvas, disparity))
    shadows: list[tuple] = []
    if props:
        _draw(r, _prisms(r, pose, (), scene, False), disparity, canvas, None, None, shadows, gain, {})
    wall = v_bottom > v_top
    readable = wall & (wall_z <= r.z_readable[1])
    first_readable = int(v_top[readable].min()) if readable.any() else h
    return shadows, int(v_bottom[wall].max()) if wall.any() else 0, first_readable


def _draw(r: _Renderer, prisms: list[_Prism], disparity: np.ndarray, canvas: np.ndarray,
          labels: np.ndarray | None, full: np.ndarray | None, shadows: list, gain: float, bands: dict) -> None:
    """Z-buffer ``prisms`` into the images: cylinders all at once, boxes one by one."""
    _draw_circles(r, [p for p in prisms if p.footprint == "circle"], disparity, canvas, labels, full, shadows,
                  gain, bands)
    for p in prisms:
        if p.footprint != "circle":
            _draw_prism(r, p, disparity, canvas, labels, full, shadows, gain, bands)


def _background(r: _Renderer, v_top: np.ndarray, v_bottom: np.ndarray, walls: tuple, floors: tuple,
                outs: tuple) -> None:
    """Fill each image of ``outs`` with its wall row (per column, ``walls``) in rows ``v_top:v_bottom``
    of each column and its floor/backdrop image (``floors``) elsewhere.

    Only the rows where some column changes between wall and floor need a per-pixel mask; above and
    below them every column agrees, and those rows are plain copies.
    """
    import cv2

    h = r.cam.height
    wall = v_bottom > v_top
    if not wall.any():
        for floor, out in zip(floors, outs):
            np.copyto(out, floor)
        return
    top0, top1 = int(v_top[wall].min()), int(v_top[wall].max())       # rows where walls start
    bot0, bot1 = int(v_bottom[wall].min()), int(v_bottom[wall].max())  # ... and end
    if not wall.all():                  # some column sees no wall: floor/backdrop from top to bottom
        top1, bot0 = h, 0
    bands = [(top0, bot1)] if top1 >= bot0 else [(top0, top1), (bot0, bot1)]
    height = np.maximum(v_bottom - v_top, 0).view(np.uint16)
    masks = []
    for a, b in bands:
        # row - top, taken as unsigned, is below the wall's height in rows only on the wall
        masks.append(((r.rows[a:b] - v_top).view(np.uint16) >= height).view(np.uint8))
    for row, floor, out in zip(walls, floors, outs):
        out[:top0] = floor[:top0]
        out[bot1:] = floor[bot1:]
        if bot1 > top0:
            cv2.repeat(row[None], bot1 - top0, 1, dst=out[top0:bot1])   # a row broadcast, faster than numpy's
        for (a, b), mask in zip(bands, masks):
            if b > a:
                cv2.copyTo(floor[a:b], mask, out[a:b])


@lru_cache(maxsize=64)
def _wall_table(walls: tuple[Wall, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The walls as arrays, once per scene: start points, directions (one row each) and colours and
    heights with an extra last entry for columns that see no wall."""
    start = np.array([(wl.x0, wl.y0) for wl in walls], np.float64).reshape(-1, 2)
    edge = np.array([(wl.x1 - wl.x0, wl.y1 - wl.y0) for wl in walls] + [(1.0, 0.0)], np.float64)
    rgb = np.array([wl.rgb for wl in walls] + [(0, 0, 0)], np.float32)
    height = np.array([wl.height_m for wl in walls] + [0.0])
    return start, edge, rgb, height


def _ray_directions(r: _Renderer, pose: Pose) -> tuple[np.ndarray, np.ndarray]:
    """World direction (dx, dy) per column of the ray P(z) = C + z * (f + tan_u * rgt), f = (c, s),
    rgt = (s, -c): z is the optical-axis depth."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return c + r.tan_u * s, s - r.tan_u * c


def _wall_depths(r: _Renderer, pose: Pose, walls: Sequence[Wall]) -> tuple[np.ndarray, np.ndarray]:
    """Nearest wall depth (z) per column and its index (len(walls) where none): all walls at once."""
    w = r.cam.width
    if not walls:
        return np.full(w, np.inf), np.zeros(w, np.int64)
    start, edge, _, _ = _wall_table(tuple(walls))
    n = len(walls)
    dx, dy = _ray_directions(r, pose)
    ex, ey = edge[:n, :1], edge[:n, 1:]
    ox, oy = start[:, :1] - pose[0], start[:, 1:] - pose[1]
    f32 = np.float32
    den = dx * (-ey).astype(f32) - dy * (-ex).astype(f32)            # solve z*d - t*e = o
    with np.errstate(divide="ignore", invalid="ignore"):
        z = (ox * (-ey) - oy * (-ex)).astype(f32) / den
        t = (dx * oy.astype(f32) - dy * ox.astype(f32)) / den
    ok = (np.abs(den) > 1e-12) & (z > _NEAR_M) & (t >= 0) & (t <= 1)
    z = np.where(ok, z, np.float32(np.inf))
    idx = np.argmin(z, axis=0)                         # the first of equally near walls, as drawn
    best = z[idx, np.arange(w)].astype(np.float64)
    idx[best == np.inf] = n
    return best, idx


def _wall_colours(r: _Renderer, pose: Pose, walls: Sequence[Wall], idx: np.ndarray,
                  z: np.ndarray) -> np.ndarray:
    """Per-column wall colour, shaded by the angle between the wall and the viewing ray."""
    w = r.cam.width
    if not walls:
        return np.zeros((w, 3), np.uint8)
    _, edge, rgb, _ = _wall_table(tuple(walls))
    dx, dy = _ray_directions(r, pose)
    nrm = np.hypot(dx, dy)
    ex, ey = edge[idx, 0], edge[idx, 1]
    el = np.hypot(ex, ey)
    cos_inc = np.abs((dx * ey - dy * ex) / (nrm * el))
    shade = 0.55 + 0.45 * cos_inc - 0.03 * np.minimum(np.where(z == np.inf, 0.0, z), 8)
    return np.clip(rgb[idx] * shade[:, None], 0, 255).astype(np.uint8)


def _prisms(r: _Renderer, pose: Pose, robots: Sequence[Pose], scene: Scene, count: bool,
            props: bool = True) -> list[_Prism]:
    """The prisms to draw: the robots' (those outside the field of view left out unless counting their
    pixels), then, with ``props``, the scene's props."""
    rig = r.rig
    look = scene.robot_look
    out: list[_Prism] = []
    cx, cy, cyaw = pose
    cc, cs = math.cos(cyaw), math.sin(cyaw)
    reach = max(look.body_radius_m, abs(markers.FRONT_OFFSET_M) + markers.CYLINDER_RADIUS_M,
                abs(markers.REAR_OFFSET_M) + markers.CYLINDER_RADIUS_M)
    sin_fov, cos_fov = math.sin(r.half_fov), math.cos(r.half_fov)

    def add_circle(x, y, radius, bottom, top, rgb, label=0):
        dx, dy = x - cx, y - cy
        out.append(_Prism("circle", (cs * dx - cc * dy, cc * dx + cs * dy), radius, (0, 0), (0, 0), bottom, top,
                          rgb, label))

    for i, (x, y, yaw) in enumerate(robots):
        dx, dy = x - cx, y - cy
        xr, zf = cs * dx - cc * dy, cc * dx + cs * dy
        # the robot's bounding circle is behind the camera or beyond either edge of the view
        if zf < _NEAR_M - reach or (-abs(xr) * cos_fov + zf * sin_fov) < -reach:
            if not count:
                continue
        add_circle(x, y, look.body_radius_m, 0.0, look.body_top_m, look.body_rgb)
        c, s = math.cos(yaw), math.sin(yaw)
        for off, rgb, label in ((markers.FRONT_OFFSET_M, look.front_rgb, 1 + 2 * i),
                                (markers.REAR_OFFSET_M, look.rear_rgb, 2 + 2 * i)):
            add_circle(x + c * off, y + s * off, markers.CYLINDER_RADIUS_M, markers.CYLINDER_BOTTOM_M,
                       markers.CYLINDER_TOP_M, rgb, label)
    for p in scene.props if props else ():
        if isinstance(p, CylinderProp):
            add_circle(p.x, p.y, p.radius_m, p.bottom_m, p.top_m, p.rgb)
        else:
            rel = p.yaw - cyaw        # box axis in the optical frame: x = -left, z = forward
            out.append(_Prism("box", to_camera(rig, pose, p.x, p.y), 0.0, (p.length_m / 2, p.width_m / 2),
                              (-math.sin(rel), math.cos(rel)), p.bottom_m, p.top_m, p.rgb, 0))
    return out


def _entry_exit(r: _Renderer, p: _Prism) -> tuple[int, int, np.ndarray, np.ndarray] | None:
    """Columns [u0, u1) the prism covers and, per column, the z where the ray enters and leaves it."""
    cam = r.cam
    xc, zc = p.cam_xz
    if p.footprint == "circle":
        reach = p.radius
    else:
        reach = math.hypot(*p.half)
    if zc - reach < _NEAR_M:
        return None
    # conservative column span from the bounding circle
    rng_ = math.hypot(xc, zc)
    beta = math.asin(min(1.0, reach / rng_))
    phi = math.atan2(xc, zc)
    lo, hi = phi - beta, phi + beta
    if hi <= -math.pi / 2 or lo >= math.pi / 2:
        return None
    u0 = max(0, int(math.floor(cam.fx * math.tan(max(lo, -1.5)) + cam.cx)))
    u1 = min(cam.width, int(math.ceil(cam.fx * math.tan(min(hi, 1.5)) + cam.cx)) + 1)
    if u1 <= u0:
        return None
    tau = r.tan_u64[u0:u1]
    if p.footprint == "circle":
        # ray z * (tau, 1) meets the circle: a z^2 - 2 b z + c = 0
        a = 1.0 + tau * tau
        b = xc * tau + zc
        disc = b * b - a * (xc * xc + zc * zc - p.radius * p.radius)
        ok = disc >= 0
        sq = np.sqrt(np.maximum(disc, 0.0))
        t1 = (b - sq) / a
        t2 = (b + sq) / a
        if not ok.all():
            t1[~ok] = np.inf
            t2[~ok] = -np.inf
    else:
        ax, az = p.axis                   # length axis; width axis is its perpendicular
        bx, bz = az, -ax
        # ray point z*(tau, 1) - centre, projected on the two axes: o + z * d
        o1, d1 = -(xc * ax + zc * az), tau * ax + az
        o2, d2 = -(xc * bx + zc * bz), tau * bx + bz
        t1 = np.full(tau.shape, -np.inf)
        t2 = np.full(tau.shape, np.inf)
        for o, d, hlf in ((o1, d1, p.half[0]), (o2, d2, p.half[1])):
            with np.errstate(divide="ignore", invalid="ignore"):
                ta = (-hlf - o) / d
                tb = (hlf - o) / d
            par = np.abs(d) < 1e-12
            inside = np.abs(o) <= hlf
            lo_t = np.where(par, np.where(inside, -np.inf, np.inf), np.minimum(ta, tb))
            hi_t = np.where(par, np.where(inside, np.inf, -np.inf), np.maximum(ta, tb))
            t1 = np.maximum(t1, lo_t)
            t2 = np.minimum(t2, hi_t)
        bad = t1 > t2
        t1 = np.where(bad, np.inf, t1)
        t2 = np.where(bad, -np.inf, t2)
    return u0, u1, t1, t2


_SHADE_LEVELS = 256


@lru_cache(maxsize=256)
def _face_palette(rgb: RGB, gain: float) -> np.ndarray:
    """Colours (256 x 3 uint8) of a lit vertical face for view-angle cosines 0..1 in 256 steps."""
    cosv = np.linspace(0.0, 1.0, _SHADE_LEVELS)
    return _rgb8((0.62 + 0.38 * cosv)[:, None] * np.asarray(rgb) * gain)


@lru_cache(maxsize=256)
def _cap_colour(rgb: RGB, factor: float) -> np.ndarray:
    return _rgb8(np.asarray(rgb) * factor)


def _cap_factor(p: _Prism, camera_height: float, gain: float) -> float:
    """Brightness of a prism's flat cap as the camera sees it: a lit top below the camera, a dark
    underside above it."""
    return (0.9 if p.top < camera_height else 0.45) * gain


@lru_cache(maxsize=64)
def _face_palettes(rgbs: tuple[RGB, ...], gain: float) -> np.ndarray:
    """``_face_palette`` of each colour, one after the other (index: colour * 256 + level)."""
    return np.concatenate([_face_palette(rgb, gain) for rgb in rgbs])


def _zbuffer_band(r: _Renderer, p: _Prism, disparity: np.ndarray, u0: int, u1: int, t1: np.ndarray,
                  t2: np.ndarray, zmin: float, zmax: float, full: np.ndarray, bands: dict,
                  d1: np.ndarray | None = None):
    """The rows a prism spans in columns ``u0:u1`` (rays enter at ``t1``, leave at ``t2``), where it is
    hit and where it is nearer than what is drawn; None when it covers nothing. Shared by boxes and
    cylinders; counts the prism's pixels for the visibility bookkeeping. Returns the disparity to write
    where the mask says: one row (the same in every row) for a side seen from within its height range.
    ``d1``: the disparity at ``t1``, if already known."""
    cam, hc = r.cam, r.rig.height_m
    a, b = hc - p.top, hc - p.bottom                     # a <= k*z <= b inside the height range
    ks = (a / zmin, a / zmax, b / zmin, b / zmax)
    v0 = max(0, math.floor(min(ks) * cam.fy + cam.cy))
    v1 = min(cam.height, math.ceil(max(ks) * cam.fy + cam.cy) + 1)
    if v1 <= v0:
        return None
    lo, hi = r.height_limits(p.bottom, p.top)
    lo, hi = lo[v0:v1], hi[v0:v1]
    t1c = t1.astype(np.float32, copy=False)[None, :]
    region = disparity[v0:v1, u0:u1]                         # disparity: nearer is larger
    if a < 0 < b:           # camera between bottom and top: no cap in sight, the side at the entry depth
        hit = t1c <= hi
        dhit = r.fb32 / t1c if d1 is None else d1[None, :]   # one row: the same in every row
    else:
        zhit = np.maximum(t1c, lo)
        hit = zhit <= np.minimum(t2.astype(np.float32, copy=False)[None, :], hi)
        dhit = r.fb32 / zhit
    closer = dhit > region
    if p.label and full is not None:
        full[p.label] += int(np.count_nonzero(hit))
        bands[p.label] = (v0, v1, u0, u1)
    closer &= hit
    if not np.count_nonzero(closer):
        return None
    return v0, v1, region, dhit, closer, lo, t1c


def _draw_prism(r: _Renderer, p: _Prism, disparity: np.ndarray, image: np.ndarray, labels: np.ndarray | None,
                full: np.ndarray, shadows: list, gain: float, bands: dict) -> None:
    """Z-buffer one box into the disparity and colour images (only its band of columns and rows)."""
    import cv2

    span = _entry_exit(r, p)
    if span is None:
        return
    u0, u1, t1, t2 = span
    hit_cols = (t1 > _NEAR_M) & (t1 < np.inf)
    if not hit_cols.all():
        if not hit_cols.any():
            return
        first, last = int(np.argmax(hit_cols)), len(hit_cols) - int(np.argmax(hit_cols[::-1]))
        u0, u1, t1, t2, hit_cols = u0 + first, u0 + last, t1[first:last], t2[first:last], hit_cols[first:last]
    hc = r.rig.height_m
    zmin = float(t1[hit_cols].min())
    band = _zbuffer_band(r, p, disparity, u0, u1, t1, t2, zmin, float(t2[hit_cols].max()), full, bands)
    if band is None:
        return
    v0, v1, region, dhit, closer, lo, t1c = band
    # shading: vertical faces by the angle between normal and view ray, caps flat
    tau = r.tan_u64[u0:u1]
    t1f = np.where(hit_cols, t1, 0.0)
    ax, az = p.axis
    bx, bz = az, -ax
    xh, zh = t1f * tau - p.cam_xz[0], t1f - p.cam_xz[1]
    u_ax = xh * ax + zh * az
    u_bx = xh * bx + zh * bz
    on_len = np.abs(np.abs(u_ax) - p.half[0]) < np.abs(np.abs(u_bx) - p.half[1])
    nx = np.where(on_len, np.sign(u_ax) * ax, np.sign(u_bx) * bx)
    nz = np.where(on_len, np.sign(u_ax) * az, np.sign(u_bx) * bz)
    view = -(nx * tau + nz) / np.sqrt(1 + tau * tau)
    level = np.rint(np.clip(view, 0.0, 1.0) * (_SHADE_LEVELS - 1)).astype(np.intp)
    face_col = _face_palette(p.rgb, gain)[level]
    cap_col = _cap_colour(p.rgb, _cap_factor(p, hc, gain))
    mask = closer.view(np.uint8)
    cv2.copyTo(cv2.repeat(dhit, v1 - v0, 1) if len(dhit) == 1 else dhit, mask, region)
    colours = np.where((t1c >= lo)[..., None], face_col[None, :], cap_col)
    cv2.copyTo(colours, mask, image[v0:v1, u0:u1])
    if labels is not None:
        cv2.copyTo(np.full(mask.shape, p.label, np.int16), mask, labels[v0:v1, u0:u1])
    first = int(np.argmax(hit_cols))
    shadows.append((u0 + first, v0, v1, float(t1[first]), zmin))


def _draw_circles(r: _Renderer, prisms: list[_Prism], disparity: np.ndarray, image: np.ndarray,
                  labels: np.ndarray | None, full: np.ndarray, shadows: list, gain: float, bands: dict) -> None:
    """``_draw_prism`` for vertical cylinders: the exact silhouette columns of all of them computed in
    one go (a frame with many robots has dozens), then each drawn near to far, so that hidden ones stop
    at the depth test before their colours are made."""
    import cv2

    if not prisms:
        return
    cam = r.cam
    xc = np.array([p.cam_xz[0] for p in prisms])
    zc = np.array([p.cam_xz[1] for p in prisms])
    rad = np.array([p.radius for p in prisms])
    rho = np.hypot(xc, zc)
    with np.errstate(invalid="ignore"):
        beta = np.arcsin(np.minimum(rad / rho, 1.0))
    phi = np.arctan2(xc, zc)
    # in front of the camera and not far outside a pinhole camera's view
    keep = (zc - rad >= _NEAR_M) & (phi + beta < 1.5) & (phi - beta > -1.5)
    with np.errstate(invalid="ignore"):
        # columns whose centre ray meets the circle (all of them: no misses to mask)
        u0 = np.maximum(0, np.ceil(cam.fx * np.tan(phi - beta) + cam.cx))
        u1 = np.minimum(cam.width, np.floor(cam.fx * np.tan(phi + beta) + cam.cx) + 1)
    keep &= u1 > u0
    order = np.flatnonzero(keep)
    if not order.size:
        return
    order = order[np.argsort(rho[order], kind="stable")]           # near to far
    u0, u1 = u0[order].astype(np.intp), u1[order].astype(np.intp)
    xc, zc, rad, rho = xc[order], zc[order], rad[order], rho[order]
    lens = u1 - u0
    ends = np.cumsum(lens)
    starts = ends - lens
    col = np.arange(int(ends[-1])) + np.repeat(u0 - starts, lens)
    tau = r.tan_u64[col]
    x, z, rr = np.repeat(xc, lens), np.repeat(zc, lens), np.repeat(rad, lens)
    a2 = 1.0 + tau * tau
    b2 = x * tau + z
    sq = np.sqrt(np.maximum(b2 * b2 - a2 * (np.repeat(rho * rho - rad * rad, lens)), 0.0))
    t1 = (b2 - sq) / a2                                  # where the ray enters and leaves the cylinder
    t2 = (b2 + sq) / a2
    # shading: the side by the angle between its normal and the view ray, the caps flat
    view = ((z - t1) + (x - t1 * tau) * tau) * (_SHADE_LEVELS - 1) / rr / np.sqrt(a2)
    np.clip(view, 0.0, _SHADE_LEVELS - 1, out=view)
    level = (view + 0.5).astype(np.intp)
    # face colours of every column at once: palettes stacked, one per colour
    rgbs = [prisms[i].rgb for i in order]
    colours = tuple(dict.fromkeys(rgbs))
    which = np.array([colours.index(rgb) for rgb in rgbs]) * _SHADE_LEVELS
    face = _face_palettes(colours, gain)[np.repeat(which, lens) + level]
    t1_32, t2_32 = t1.astype(np.float32), t2.astype(np.float32)
    d1_32 = r.fb32 / t1_32                                   # disparity of the side
    zmin, zmax = np.minimum.reduceat(t1, starts), np.maximum.reduceat(t2, starts)
    hc = r.rig.height_m
    drawn = [prisms[i] for i in order]
    bottom = np.array([p.bottom for p in drawn])
    top = np.array([p.top for p in drawn])
    # the rows each can cover (a <= k z <= b inside its height range), as ``_zbuffer_band`` finds them
    a, b = hc - top, hc - bottom
    ks = np.stack((a / zmin, a / zmax, b / zmin, b / zmax))
    v0a = np.maximum(0, np.floor(ks.min(axis=0) * cam.fy + cam.cy)).astype(np.intp)
    v1a = np.minimum(cam.height, np.ceil(ks.max(axis=0) * cam.fy + cam.cy) + 1).astype(np.intp)
    limits = {key: r.height_limits(*key) for key in {(p.bottom, p.top) for p in drawn}}
    if _ZBUFFER is not None:
        _draw_cylinders_compiled(r, drawn, starts, u0, lens, v0a, v1a, t1, t1_32, t2_32, face, zmin, limits,
                                 disparity, image, labels, full, shadows, gain, bands)
        return
    rows = np.maximum(v1a - v0a, 0)
    small = rows * lens <= _BATCH_PX
    side_only = ((a < 0) & (b > 0)).tolist()       # camera between bottom and top: no cap in sight
    fb32 = r.fb32
    starts_, ends_, u0_, u1_, v0s, v1s = (x.tolist() for x in (starts, ends, u0, u1, v0a, v1a))
    for i in np.flatnonzero(~small & (rows > 0)).tolist():        # big ones one by one, near to far
        s, e, c0, c1, v0, v1 = starts_[i], ends_[i], u0_[i], u1_[i], v0s[i], v1s[i]
        p = drawn[i]
        lo, hi = limits[(p.bottom, p.top)]
        lo, hi = lo[v0:v1], hi[v0:v1]
        t1c = t1_32[None, s:e]
        region = disparity[v0:v1, c0:c1]                     # disparity: nearer is larger
        if side_only[i]:
            hit = t1c <= hi
            dhit = d1_32[None, s:e]                          # one row: the same in every row
        else:
            zhit = np.maximum(t1c, lo)
            hit = zhit <= np.minimum(t2_32[None, s:e], hi)
            dhit = fb32 / zhit
        closer = dhit > region
        if full is not None and p.label:
            full[p.label] += int(np.count_nonzero(hit))
            bands[p.label] = (v0, v1, c0, c1)
        closer &= hit
        if not np.count_nonzero(closer):
            continue
        mask = closer.view(np.uint8)
        colours = cv2.repeat(face[None, s:e], v1 - v0, 1)
        if side_only[i]:
            cv2.copyTo(cv2.repeat(dhit, v1 - v0, 1), mask, region)
        else:
            cv2.copyTo(dhit, mask, region)
            cap = r.cap_block(p.rgb, _cap_factor(p, hc, gain), v1 - v0, c1 - c0)
            cv2.copyTo(cap, (t1c < lo).view(np.uint8), colours)
        cv2.copyTo(colours, mask, image[v0:v1, c0:c1])
        if labels is not None:
            cv2.copyTo(np.full(mask.shape, p.label, np.int16), mask, labels[v0:v1, c0:c1])
        shadows.append((c0, v0, v1, float(t1[s]), float(zmin[i])))
    batch = np.flatnonzero(small & (rows > 0))
    if batch.size:
        _draw_small_cylinders(r, drawn, batch, starts, u0, v0a, rows[batch], lens[batch], t1, t1_32, t2_32, face,
                              zmin, limits, disparity, image, labels, full, shadows, gain, bands)


def _draw_cylinders_compiled(r: _Renderer, drawn: list[_Prism], starts: np.ndarray, u0: np.ndarray,
                             cols: np.ndarray, v0: np.ndarray, v1: np.ndarray, t1: np.ndarray, t1_32: np.ndarray,
                             t2_32: np.ndarray, face: np.ndarray, zmin: np.ndarray, limits: dict,
                             disparity: np.ndarray, image: np.ndarray, labels: np.ndarray | None,
                             full: np.ndarray | None, shadows: list, gain: float, bands: dict) -> None:
    """The loop of ``_draw_circles`` (and ``_draw_small_cylinders``) for every cylinder in ``drawn``, near to
    far, by the compiled ``_zbuffer.draw_cylinders``: the same pixels, pixel counts and shadows."""
    lo_rows, hi_rows, limit_row0 = _stacked_limits(limits, drawn, disparity.shape[0])
    hc = r.rig.height_m
    cap_rgb = np.array([_cap_colour(p.rgb, _cap_factor(p, hc, gain)) for p in drawn], np.uint8)
    label = np.array([p.label for p in drawn], np.int16)
    hits, written = np.zeros(len(drawn), np.int64), np.zeros(len(drawn), np.int64)
    _ZBUFFER.draw_cylinders(disparity, image, labels, t1_32, t2_32, face, lo_rows, hi_rows, starts, u0, cols,
                            v0, v1, limit_row0, cap_rgb, label, float(r.fb32), hits, written)
    if full is not None:
        some = np.flatnonzero(v1 > v0)
        _count_marker_pixels([drawn[i] for i in some.tolist()], hits[some], v0[some], v1[some], u0[some], cols[some],
                             full, bands)
    for i in np.flatnonzero(written).tolist():
        s, c0 = int(starts[i]), int(u0[i])
        shadows.append((c0, int(v0[i]), int(v1[i]), float(t1[s]), float(zmin[i])))


def _stacked_limits(limits: dict, members: list[_Prism], h: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The per-row depth limits (``height_limits``) of every height range in ``limits``, one range after the
    other, and for each of ``members`` where its range's rows start in them."""
    keys = list(limits)
    lo = np.concatenate([limits[k][0].ravel() for k in keys])
    hi = np.concatenate([limits[k][1].ravel() for k in keys])
    return lo, hi, np.array([keys.index((p.bottom, p.top)) * h for p in members], np.intp)


def _count_marker_pixels(members: list[_Prism], hits: np.ndarray, v0: np.ndarray, v1: np.ndarray, u0: np.ndarray,
                         cols: np.ndarray, full: np.ndarray, bands: dict) -> None:
    """For each labelled cylinder of ``members`` (drawn in rows ``v0:v1``, columns ``u0:u0 + cols``): its
    pixels hit, visible or not, into ``full``, and its band, where ``_render`` counts the visible ones."""
    for j, p in enumerate(members):
        if p.label:
            full[p.label] += int(hits[j])
            c0 = int(u0[j])
            bands[p.label] = (int(v0[j]), int(v1[j]), c0, c0 + int(cols[j]))


_BATCH_PX = 1500
"""Cylinders whose band (rows x columns) has at most this many pixels are z-buffered all at once, pixel
by pixel in flat arrays; bigger ones one by one in their band. Most cylinders in a crowded view are far
and small, and one by one each would cost a dozen numpy calls' overhead for a few hundred pixels."""


def _draw_small_cylinders(r: _Renderer, drawn: list[_Prism], batch: np.ndarray, starts: np.ndarray,
                          u0: np.ndarray, v0: np.ndarray, rows: np.ndarray, cols: np.ndarray, t1: np.ndarray,
                          t1_32: np.ndarray, t2_32: np.ndarray, face: np.ndarray, zmin: np.ndarray,
                          limits: dict, disparity: np.ndarray, image: np.ndarray, labels: np.ndarray | None,
                          full: np.ndarray | None, shadows: list, gain: float, bands: dict) -> None:
    """The loop of ``_draw_circles`` for the cylinders ``batch`` (indices into ``drawn``, near to far) in one
    go: every pixel of their bands is a candidate, the nearest hit per pixel wins (the first, nearest
    cylinder on a tie, as one by one), and only pixels nearer than what is drawn already are written.
    Per-column values (``t1_32``, ``t2_32``, ``face``) are indexed from ``starts`` as in ``_draw_circles``."""
    h, w = disparity.shape
    hc = r.rig.height_m
    # one segment per (cylinder, row), ``cols`` pixels long
    members = [drawn[i] for i in batch.tolist()]
    lo_tab, hi_tab, key_of = _stacked_limits(limits, members, h)
    seg_cyl = np.repeat(np.arange(batch.size), rows)                  # position in ``batch``
    first = np.cumsum(rows) - rows
    seg_row = np.arange(seg_cyl.size) - np.repeat(first - v0[batch], rows)
    seg_len = cols[seg_cyl]
    seg_lo, seg_hi = lo_tab[key_of[seg_cyl] + seg_row], hi_tab[key_of[seg_cyl] + seg_row]
    px_first = np.cumsum(seg_len) - seg_len
    col = np.arange(int(px_first[-1] + seg_len[-1])) - np.repeat(px_first, seg_len)   # column in the band
    colidx = np.repeat(starts[batch][seg_cyl], seg_len) + col          # into the per-column arrays
    pix = np.repeat(seg_row * w + u0[batch][seg_cyl], seg_len) + col   # into the flat image
    cyl = np.repeat(seg_cyl, seg_len)
    t1p = t1_32[colidx]
    lop = np.repeat(seg_lo, seg_len)
    zhit = np.maximum(t1p, lop)
    hit = zhit <= np.minimum(t2_32[colidx], np.repeat(seg_hi, seg_len))
    dhit = r.fb32 / zhit
    flat = disparity.reshape(-1)
    valid = hit & (dhit > flat[pix])
    if full is not None:
        _count_marker_pixels(members, np.bincount(cyl[hit], minlength=batch.size), v0[batch], v0[batch] + rows,
                             u0[batch], cols, full, bands)
    sel = np.flatnonzero(valid)
    if not sel.size:
        return
    pix, dhit, cyl, colidx = pix[sel], dhit[sel], cyl[sel], colidx[sel]
    np.maximum.at(flat, pix, dhit)
    win = np.flatnonzero(flat[pix] == dhit)[::-1]       # far to near: on a tie the nearer is written last
    pix, cyl = pix[win], cyl[win]
    # pixels moved as 3-byte items (numpy copies rows of 3 uint8 a few times slower)
    colours = np.ascontiguousarray(face).view("V3").ravel()[colidx[win]]
    cap = t1p[sel][win] < lop[sel][win]                 # the ray meets the top or bottom, not the side
    if cap.any():
        cap_rgb = np.array([_cap_colour(p.rgb, _cap_factor(p, hc, gain)) for p in members], np.uint8)
        colours[cap] = cap_rgb.view("V3").ravel()[cyl[cap]]
    image.reshape(-1).view("V3")[pix] = colours
    if labels is not None:
        labels.reshape(-1)[pix] = np.array([p.label for p in members], np.int16)[cyl]
    for j in np.flatnonzero(np.bincount(cyl, minlength=batch.size)).tolist():
        i = int(batch[j])
        s, c0, top_row = int(starts[i]), int(u0[i]), int(v0[i])
        shadows.append((c0, top_row, top_row + int(rows[j]), float(t1[s]), float(zmin[i])))


def _depth_noise(r: _Renderer, disparity: np.ndarray, shadows: list, rng: np.random.Generator,
                 top: int, floor: int, flat: np.ndarray | None = None) -> np.ndarray:
    """Kinect-like measurement of the true depth: shadows, noise, quantisation, holes, range limits.

    Works in disparity (fb / z) like the sensor: noise and dropouts come from the bank at a random
    offset, rounding to 1/subpixel steps quantises, and readings outside the range become 0. Rows from
    ``floor`` down are bare floor: their readings come from ``floor_depth_bank`` at a random column.
    Rows above ``top`` hold nothing in range (not even within the noise of it) and read 0.
    ``disparity`` (the z-buffer, a scratch buffer) is modified in place; the returned depth image is new,
    or a view of ``flat`` (at least h * w + ``registration_px`` values) if given.
    """
    s = r.sensor
    h, w = disparity.shape
    fb1 = s.focal_baseline_px_m
    # the projector sits beside the IR camera: the background d columns left of a nearer object gets
    # no pattern while d <= fb * (1/z_object - 1/z_background), i.e. beyond the depth
    # 1 / (1/z_object - d/fb) (and at least 5 cm behind the object); nothing behind an object beyond
    # the range is in range anyway
    cast = [(max(0, u_left - int(fb1 / zf) - 1), u_left, v0, v1, zf)
            for u_left, v0, v1, zf, _ in (shadows if s.shadows else ()) if zf < s.max_m]
    cast = [c for c in cast if c[0] < c[1]]
    if cast:                        # the limits of all shadows at once, then each shadow's block
        widths = np.array([u_left - a for a, u_left, _, _, _ in cast])
        ends = np.cumsum(widths)
        d = (np.repeat(ends, widths) - np.arange(int(ends[-1]))).astype(np.float64)   # width .. 1 each
        zf = np.repeat(np.array([c[4] for c in cast]), widths)
        room = 1.0 / zf - d / fb1
        beyond = np.where(room > 0, 1.0 / np.maximum(room, 1e-12), np.inf)
        limits = r.fb32 / np.maximum(beyond, zf + 0.05).astype(np.float32)           # as a disparity
        for (a, u_left, v0, v1, _), e, w_ in zip(cast, ends.tolist(), widths.tolist()):
            blk = disparity[v0:v1, a:u_left]
            blk[blk <= limits[None, e - w_:e]] = 0

    k = max(0, int(s.registration_px))          # depth-to-colour registration error (columns)
    n = floor * w
    off = int(rng.integers(0, r.disparity_bank.size - n + 1))
    # ``flat[k:k + n]`` as an image is ``out`` moved k columns right: computing it contiguously shifts
    # depth against colour; what wraps into each row's first k columns is cleared afterwards
    flat = np.empty(h * w + k, np.float32) if flat is None else flat[:h * w + k]
    out = flat[:h * w].reshape(h, w)
    flat[:top * w + k] = 0
    _measure(r, disparity[top:floor], r.disparity_bank[off + top * w:off + n].reshape(floor - top, w),
             flat[top * w + k:k + n].reshape(floor - top, w))
    if floor < h:
        col = int(rng.integers(0, r.extra - k + 1))
        out[floor:, k:] = r.floor_depth_bank()[floor:, col:col + w - k]
    if k:
        out[:, :k] = 0
    return out


def _measure(r: _Renderer, disparity: np.ndarray, noise: np.ndarray, out: np.ndarray) -> np.ndarray:
    """What the sensor reads for the true ``disparity`` plus ``noise`` (both in 1/subpixel steps):
    rounded to a step, as a depth, 0 outside the range (also no surface and dropouts); into ``out``."""
    import cv2

    s = r.sensor
    with np.errstate(divide="ignore"):
        np.add(disparity, noise, out=out)
        np.rint(out, out=out)
        np.divide(r.fb32, out, out=out)                             # no surface (0) -> inf -> no reading
    # readings outside [min, max] (also inf, and the negative ones the dropouts made) become 0
    cv2.threshold(out, float(s.max_m), 0, cv2.THRESH_TOZERO_INV, dst=out)
    cv2.threshold(out, float(s.min_m) - 1e-6, 0, cv2.THRESH_TOZERO, dst=out)
    return out
