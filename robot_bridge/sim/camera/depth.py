"""Stage 3 of a frame: the depth sensor's measurement, noise, disparity quantisation, dropouts and shadows.

Moved unchanged from ``robot_bridge/sim/camera.py`` (issue 23); the package's ``__init__`` says how the
camera works. ``r: _Renderer`` is ``renderer._Renderer``, named but not imported: the renderer imports the
stages.
"""
from __future__ import annotations

import numpy as np


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
