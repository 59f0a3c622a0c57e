"""Stage 1 of a frame: what does not move, the floor, the walls (and a still camera's props), per column.

Moved unchanged from ``robot_bridge/sim/camera.py`` (issue 23); the package's ``__init__`` says how the
camera works. ``r: _Renderer`` is ``renderer._Renderer``, named but not imported: the renderer imports the
stages.
"""
from __future__ import annotations

import math
from functools import lru_cache
from typing import Sequence

import numpy as np

from robot_bridge.sim.camera.objects import _draw, _prisms
from robot_bridge.sim.camera.scene import Pose, Scene, Wall, _NEAR_M, _rgb8


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
