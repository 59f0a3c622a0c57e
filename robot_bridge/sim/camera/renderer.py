"""Per-camera constants, noise banks, static-layer cache and scratch buffers (one ``_Renderer`` per rig).

Moved unchanged from ``robot_bridge/sim/camera.py`` (issue 23); the package's ``__init__`` says how the
camera works.
"""
from __future__ import annotations

import math
import threading
import weakref
from collections import OrderedDict
from functools import lru_cache

import numpy as np

from robot_bridge.sim.camera.background import _static_layers
from robot_bridge.sim.camera.depth import _measure
from robot_bridge.sim.camera.objects import _cap_colour
from robot_bridge.sim.camera.scene import CameraRig, DepthSensor, Pose, RGB, Scene, _rgb8


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
        self._scenes_watched: set[int] = set()      # ids of live scenes whose layers go when they do
        self._poses_seen: OrderedDict[tuple, None] = OrderedDict()
        self._static_lock = threading.RLock()       # re-entrant: a scene may die (and _forget run) in a GC pass here
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
            if kept is not None and kept[0]() is scene:
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
                self._watch(scene)
                self._static[key] = (weakref.ref(scene), canvas.copy(), disparity.copy(), tuple(shadows),
                                     floor_from, wall_readable)
                if len(self._static) > 32:
                    self._static.popitem(last=False)
        return shadows, floor_from, wall_readable, again

    def _watch(self, scene: Scene) -> None:
        """Drop ``scene``'s static layers once the scene is gone (its world ended): a process that runs
        world after world (``faultmas eval``, the soak) kept up to 32 layers of worlds long gone, 2 MiB
        each, and their scenes with them (issue 22's soak). Called with ``_static_lock`` held."""
        if id(scene) not in self._scenes_watched:
            self._scenes_watched.add(id(scene))
            weakref.finalize(scene, _forget_scene, weakref.ref(self), id(scene))

    def _forget(self, scene_id: int) -> None:
        with self._static_lock:
            self._scenes_watched.discard(scene_id)
            for key in [k for k in self._static if k[1] == scene_id]:
                del self._static[key]
            for key in [k for k in self._poses_seen if k[1] == scene_id]:
                del self._poses_seen[key]

    def scratch(self) -> tuple[np.ndarray, np.ndarray]:
        """This thread's colour and depth buffers (re-used frame after frame)."""
        bufs = getattr(self._local, "bufs", None)
        if bufs is None:
            h, w = self.cam.height, self.cam.width
            bufs = self._local.bufs = (np.empty((h, w, 3), np.uint8), np.empty((h, w), np.float32))
        return bufs


def _forget_scene(renderer: "weakref.ref[_Renderer]", scene_id: int) -> None:
    """A scene died: its renderer (if it still exists) drops what it kept of it."""
    alive = renderer()
    if alive is not None:
        alive._forget(scene_id)


@lru_cache(maxsize=32)
def _renderer(rig: CameraRig, sensor: DepthSensor) -> _Renderer:
    return _Renderer(rig, sensor)
