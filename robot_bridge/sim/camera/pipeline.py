"""One frame, stage after stage (background, objects, colour noise, depth): ``render`` and its counters.

Moved unchanged from ``robot_bridge/sim/camera.py`` (issue 23); the package's ``__init__`` says how the
camera works.
"""
from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from robot_bridge.sim.camera.depth import _depth_noise
from robot_bridge.sim.camera.objects import _draw, _prisms
from robot_bridge.sim.camera.renderer import _renderer
from robot_bridge.sim.camera.scene import CameraRig, Pose, Scene
from robot_bridge.sim.camera.truth import true_view


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
