"""Stage 2 of a frame: the vertical prisms (robot bodies, marker cylinders, props) z-buffered into the images.

Moved unchanged from ``robot_bridge/sim/camera.py`` (issue 23); the package's ``__init__`` says how the
camera works. ``r: _Renderer`` is ``renderer._Renderer``, named but not imported: the renderer imports the
stages.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Sequence

import numpy as np

from perception import markers
from robot_bridge.sim import zbuffer
from robot_bridge.sim.camera.scene import CylinderProp, Pose, RGB, Scene, _NEAR_M, _rgb8
from robot_bridge.sim.camera.truth import to_camera


_ZBUFFER = zbuffer.load()   # the compiled cylinder loop, or None: numpy draws (same pixels)


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


def _draw(r: _Renderer, prisms: list[_Prism], disparity: np.ndarray, canvas: np.ndarray,
          labels: np.ndarray | None, full: np.ndarray | None, shadows: list, gain: float, bands: dict) -> None:
    """Z-buffer ``prisms`` into the images: cylinders all at once, boxes one by one."""
    _draw_circles(r, [p for p in prisms if p.footprint == "circle"], disparity, canvas, labels, full, shadows,
                  gain, bands)
    for p in prisms:
        if p.footprint != "circle":
            _draw_prism(r, p, disparity, canvas, labels, full, shadows, gain, bands)


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
