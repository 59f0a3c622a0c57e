"""Find robots by their two coloured cylinders in an RGB-D frame; estimate bearing, depth and heading.

Pipeline (OpenCV on real pixel arrays): HSV thresholds per colour, morphological opening and closing,
connected components, then per blob a *cylinder* measurement rather than a box centre:

* the axis bearing is the middle of the silhouette's two edge angles (exact for a circle seen in
  perspective); when one edge is hidden by something nearer, the axis is placed one expected
  half-width from the visible edge instead;
* the axis range comes from every valid depth pixel of the blob, each corrected for where on the
  curved surface it lies (law of cosines with the 0.03 m radius), then a robust mean; when the depth
  image has no reading there (closer than the Kinect's 0.8 m), from the silhouette's angular width.

A cylinder without a range of its own (in a projector shadow, closer than 0.8 m and cut by the image
border, or only a sliver beside its partner) is placed on the circle of the spacing around its partner
where its silhouette edges and top edge fit, unless another place fits about as well.

Front/rear pairs must be 0.20-0.26 m apart in 3D; the heading is fitted on the circle |h| = 0.227 m
weighting range (noisy) and cross-range (precise) errors separately. Frame: x right, y down, z forward.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from perception import markers
from perception.camera import CameraModel
from perception.markers import HsvRange


@dataclass(frozen=True)
class DetectorConfig:
    """Colours, sizes and tolerances; defaults match ``perception.markers`` (orange front, blue rear)."""

    front_hsv: HsvRange = markers.ORANGE_HSV
    rear_hsv: HsvRange = markers.BLUE_HSV
    front_name: str = markers.FRONT_COLOUR
    rear_name: str = markers.REAR_COLOUR
    spacing_m: float = markers.CYLINDER_SPACING_M
    spacing_range_m: tuple[float, float] = markers.SPACING_RANGE_M
    radius_m: float = markers.CYLINDER_RADIUS_M
    height_m: float = markers.CYLINDER_TOP_M - markers.CYLINDER_BOTTOM_M
    kernel_px: int = 5                  # ellipse for opening and closing (the seed paper's 5x5)
    min_area_px: int = 20
    max_size_ratio: float = 1.7         # blob larger than this times a whole cylinder at its range: not ours
    min_depth_px: int = 6
    max_top_step_m: float = 0.08        # the two cylinder tops are level on one robot
    occlusion_step_m: float = 0.06      # a neighbour this much nearer hides a blob's edge
    pixel_sigma_px: float = 0.35        # edge localisation noise, for the heading fit
    max_size_range_m: float = 1.3       # range from silhouette width only this close (no depth readings)


@dataclass(frozen=True)
class Blob:
    """One colour component measured as a vertical cylinder (camera frame, metres and pixels)."""

    colour: str
    area_px: int
    bbox: tuple[int, int, int, int]     # x, y, w, h
    u: float                            # pixel column of the axis
    v: float                            # pixel row of the blob centroid
    x_m: float
    z_m: float
    range_m: float
    range_sigma_m: float
    cross_sigma_m: float
    top_y_m: float | None               # optical-frame y (down) of the visible top edge
    depth_px: int                       # depth readings used
    from_size: bool                     # range from the silhouette width (no depth readings)
    occluded: str                       # "", "left", "right" or "both"
    ranged: bool                        # False: bearing only (x_m, z_m, range_m are NaN)
    phi_left: float                     # silhouette edge angles (radians, + right)
    phi_right: float
    height_px: int
    clipped: bool                       # touches the top or bottom image border
    sides: tuple[float, float]          # depth beside the left and right edges (-1 border, NaN none)
    placed: bool = False                # range from the partner cylinder (no depth of its own)
    mixed: bool = False                 # depth readings from more than one surface (merged blobs)
    mask: np.ndarray | None = field(default=None, repr=False, compare=False)    # bbox-sized pixels


@dataclass(frozen=True)
class Detection:
    """A robot seen by the camera. Optical frame: x right, y down, z forward; angles in degrees."""

    angle_deg: float        # bearing of the midpoint of the two axes, degrees(atan2(x, z)), + right
    depth_m: float          # mean optical-axis depth z of the two axes
    yaw_deg: float          # degrees(atan2(hx, hz)), h = front - rear: 0 facing away, 90 moving right
    x_m: float              # midpoint of the axes
    z_m: float
    front_px: tuple[float, float]
    rear_px: tuple[float, float]
    spacing_m: float        # measured axis distance
    confidence: float       # 0..1
    front: Blob = field(repr=False, compare=False)
    rear: Blob = field(repr=False, compare=False)

    @property
    def pixel(self) -> tuple[float, float]:
        """Midpoint of the two axes' pixel positions."""
        return ((self.front_px[0] + self.rear_px[0]) / 2, (self.front_px[1] + self.rear_px[1]) / 2)


@dataclass(frozen=True)
class DetectionResult:
    """``detection`` (best robot) or None with a short machine-friendly ``reason``; ``all`` robots seen."""

    detection: Detection | None
    reason: str = ""
    all: tuple[Detection, ...] = ()
    blobs: tuple[Blob, ...] = field(default=(), repr=False)

    @property
    def found(self) -> bool:
        return self.detection is not None


def detect(rgb: np.ndarray, depth: np.ndarray, camera: CameraModel,
           config: DetectorConfig | None = None) -> DetectionResult:
    """The best robot in view (the pair closest to the nominal spacing), or None and why.

    ``rgb``: H x W x 3 uint8 in RGB order (ROS ``rgb8``); ``depth``: H x W float32 metres, 0 = no reading.
    """
    return _run(rgb, depth, camera, config or DetectorConfig(), every=False)


def detect_all(rgb: np.ndarray, depth: np.ndarray, camera: CameraModel,
               config: DetectorConfig | None = None) -> DetectionResult:
    """Every robot in view (``.all``, best first; each blob used once); ``.detection`` is the best."""
    return _run(rgb, depth, camera, config or DetectorConfig(), every=True)


def _run(rgb: np.ndarray, depth: np.ndarray, camera: CameraModel, cfg: DetectorConfig,
         every: bool) -> DetectionResult:
    import cv2

    _check_inputs(rgb, depth, camera)
    hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)
    kernel = _kernel(cfg.kernel_px)
    depth = np.ascontiguousarray(depth, dtype=np.float32)
    cam = camera
    fronts = _blobs(hsv, depth, camera, cfg, cfg.front_hsv, cfg.front_name, kernel)
    rears = _blobs(hsv, depth, camera, cfg, cfg.rear_hsv, cfg.rear_name, kernel) if fronts else []
    blobs = tuple(fronts + rears)
    pairs = _pairs(fronts, rears, cam, cfg) if fronts and rears else []
    if not pairs and fronts and rears:      # merged look-alikes can hide a pair: retry with depth layers
        fronts2 = _resplit(fronts, depth, cam, cfg)
        rears2 = _resplit(rears, depth, cam, cfg)
        if fronts2 is not fronts or rears2 is not rears:
            pairs = _pairs(fronts2, rears2, cam, cfg)
    if not pairs:                   # a cylinder left as a sliver beside a nearer one: too thin to open
        fronts3 = fronts + _slivers(hsv, depth, cam, cfg, cfg.front_hsv, cfg.front_name, kernel)
        if fronts3:
            rears3 = rears + _slivers(hsv, depth, cam, cfg, cfg.rear_hsv, cfg.rear_name, kernel)
            if (len(fronts3), len(rears3)) != (len(fronts), len(rears)) and rears3:
                pairs = _pairs(fronts3, rears3, cam, cfg)
    if not pairs:
        if not fronts:
            return DetectionResult(None, f"no_{cfg.front_name}_blob")
        if not rears:
            return DetectionResult(None, f"no_{cfg.rear_name}_blob", blobs=blobs)
        return DetectionResult(None, "no_pair_within_spacing", blobs=blobs)
    pairs.sort(key=lambda p: p[0])
    found: list[Detection] = []
    used: set[int] = set()
    for _, fid, rid, f, r, d in pairs:
        if fid in used or rid in used:
            continue
        found.append(_pose(f, r, d, camera, cfg))
        used.update((fid, rid))
        if not every:
            break
    return DetectionResult(found[0], "", tuple(found), blobs)


def _slivers(hsv: np.ndarray, depth: np.ndarray, cam: CameraModel, cfg: DetectorConfig, rng: HsvRange,
             name: str, kernel: np.ndarray | None) -> list[Blob]:
    """Upright strips of the colour narrower than the opening kernel (which removes them), as
    bearing-only blobs: their few depth pixels sit on the rim, so only a partner may place them."""
    import cv2

    if kernel is None:
        return []
    k = kernel.shape[0]
    raw = colour_mask(hsv, rng, None)
    upright = cv2.morphologyEx(raw, cv2.MORPH_OPEN, np.ones((2 * k, 2), np.uint8))
    upright &= ~cv2.dilate(colour_mask(hsv, rng, kernel), kernel)      # only what the opening lost
    out = []
    for x, y, sub, area, v_c in _components(upright, cfg.min_area_px):
        if sub.shape[1] >= k:
            continue
        blob = _measure(sub, x, y, v_c, depth, cam, cfg, name, area)
        if blob is not None:
            out.append(replace(blob, x_m=math.nan, z_m=math.nan, range_m=math.nan, range_sigma_m=math.inf,
                               cross_sigma_m=math.inf, top_y_m=None, depth_px=0, from_size=False,
                               ranged=False))
    return out


def _resplit(blobs: list[Blob], depth: np.ndarray, cam: CameraModel, cfg: DetectorConfig) -> list[Blob]:
    """The blobs with every multi-layer one replaced by its depth layers (same list if none split)."""
    out, changed = [], False
    for b in blobs:
        x, y, w, h = b.bbox
        parts = _split_by_depth(b.mask, x, y, depth, cam, cfg, b.colour) if b.mask is not None else []
        if parts:
            out.extend(parts)
            changed = True
        else:
            out.append(b)
    return out if changed else blobs


def _pairs(fronts: list[Blob], rears: list[Blob], cam: CameraModel, cfg: DetectorConfig) -> list[tuple]:
    """Candidate (score, front id, rear id, front, rear, spacing) pairs, best (lowest score) first."""
    out = []
    for f in fronts:
        for r in rears:
            if f.ranged and r.ranged:
                d = math.hypot(f.x_m - r.x_m, f.z_m - r.z_m)
                if cfg.spacing_range_m[0] <= d <= cfg.spacing_range_m[1] and (
                        f.top_y_m is None or r.top_y_m is None
                        or abs(f.top_y_m - r.top_y_m) <= cfg.max_top_step_m):
                    out.append((abs(d - cfg.spacing_m), id(f), id(r), f, r, d))
                    continue
                # a sliver (hidden on both sides) or a blob with few readings: let its partner place it
                weak = [b for b in (f, r) if b.occluded == "both" or b.depth_px < 15 or b.from_size]
                if len(weak) != 1:
                    continue
                known, other = (r, f) if weak[0] is f else (f, r)
                placed = _place_on_circle(known, other, cam, cfg)
                if placed is not None:
                    pf, pr = (known, placed) if known is f else (placed, known)
                    out.append((0.04, id(f), id(r), pf, pr, cfg.spacing_m))
            elif f.ranged or r.ranged:
                known, other = (f, r) if f.ranged else (r, f)
                placed = _place_on_circle(known, other, cam, cfg)
                if placed is not None:
                    pf, pr = (known, placed) if f.ranged else (placed, known)
                    out.append((0.03, id(f), id(r), pf, pr, cfg.spacing_m))
    out.sort(key=lambda p: p[0])
    return out


def _place_on_circle(known: Blob, other: Blob, cam: CameraModel, cfg: DetectorConfig) -> Blob | None:
    """Put a cylinder without depth readings on the circle of radius ``spacing`` around its partner.

    Each point of the circle predicts where the cylinder's silhouette edges and its top edge appear
    (the two tops are at one height; a top cut off by the image border is left out); the best point
    must explain the pixels, and no clearly different point may explain them about as well (else:
    ambiguous, None).
    """
    top_seen = other.bbox[1] > 0                        # else clipped by the image's top border
    if known.top_y_m is None and top_seen:
        return None
    r = cfg.radius_m
    bx = known.x_m + cfg.spacing_m * np.sin(_GRID)
    bz = known.z_m + cfg.spacing_m * np.cos(_GRID)
    rho = np.hypot(bx, bz)
    ok = (bz > 0.2) & (rho > r + 0.1)
    rho = np.where(ok, rho, 1.0)
    phi = np.arctan2(bx, bz)
    half = np.arcsin(np.minimum(1.0, r / rho))
    limit = rho - r - cfg.occlusion_step_m
    cost = np.zeros_like(rho)
    for side, meas, pred, z_side in (("left", other.phi_left, phi - half, other.sides[0]),
                                     ("right", other.phi_right, phi + half, other.sides[1])):
        res = (meas - pred) * cam.fx / 0.6                     # pixels / sigma
        outward = res * (-1.0 if side == "left" else 1.0)      # measured edge beyond the prediction
        if z_side != z_side:                                   # no reading beside it: maybe hidden
            cost += np.maximum(outward, 0.0) ** 2 + (np.minimum(outward, 0.0) / 20.0) ** 2
            continue
        hidden = (z_side == -1.0) | (z_side < limit)
        cost += np.where(hidden, np.maximum(outward, 0.0) ** 2, res * res)
    if top_seen:
        v_top = cam.cy + cam.fy * known.top_y_m / np.maximum((rho - r) * np.cos(phi), 0.05)
        cost += ((other.bbox[1] - 0.5 - v_top) / 0.8) ** 2
    cost = np.where(ok, cost, np.inf)
    k = int(np.argmin(cost))
    if not cost[k] < 12.0:
        return None
    if _ambiguous(cost, k, bx, bz, cost[k] + 6.0):
        return None                                     # another place fits about as well
    rho_k, phi_k = float(rho[k]), float(phi[k])
    if not _size_plausible(other.bbox[2], other.bbox[3], other.area_px, rho_k, cam, cfg):
        return None
    occluded = _occluded_sides(other.sides, rho_k, cfg)
    return replace(other, u=cam.cx + cam.fx * math.tan(phi_k), x_m=float(bx[k]), z_m=float(bz[k]),
                   range_m=rho_k, range_sigma_m=0.01 + 0.005 * rho_k,
                   cross_sigma_m=rho_k * cfg.pixel_sigma_px / cam.fx * 2,
                   top_y_m=known.top_y_m, occluded=occluded, ranged=True, placed=True)


def _ambiguous(cost: np.ndarray, k: int, bx: np.ndarray, bz: np.ndarray, bar: float,
               spread_m: float = 0.10) -> bool:
    """Whether points other than the minimum ``k``'s own valley fit under ``bar`` (a second
    explanation of the pixels), or the valley itself reaches further than ``spread_m`` from ``k``.

    Anywhere in the valley explains the pixels; the pair's midpoint moves half as far as the placed
    cylinder, so 0.10 m keeps it within 5 cm, half the 0.1 m a detection may be off at most.
    """
    n = cost.size
    below = cost < bar
    if below.all():
        return True
    # the valley: the run of grid points under the bar around k (the grid is a closed circle)
    right = k
    while below[(right + 1) % n] and (right + 1) % n != k:
        right += 1
    left = k
    while below[(left - 1) % n]:
        left -= 1
    valley = np.arange(left, right + 1) % n
    if np.count_nonzero(below) > valley.size:
        return True
    return float(np.hypot(bx[valley] - bx[k], bz[valley] - bz[k]).max()) > spread_m


def _check_inputs(rgb: np.ndarray, depth: np.ndarray, camera: CameraModel) -> None:
    if not isinstance(rgb, np.ndarray) or rgb.dtype != np.uint8 or rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ValueError(f"rgb must be an H x W x 3 uint8 array, got {getattr(rgb, 'shape', None)} "
                         f"{getattr(rgb, 'dtype', type(rgb).__name__)}")
    if not isinstance(depth, np.ndarray) or depth.ndim != 2:
        raise ValueError(f"depth must be an H x W array of metres, got {getattr(depth, 'shape', None)}")
    if depth.shape != rgb.shape[:2]:
        raise ValueError(f"depth is {depth.shape[1]}x{depth.shape[0]} but rgb is {rgb.shape[1]}x{rgb.shape[0]}")
    if (camera.width, camera.height) != (rgb.shape[1], rgb.shape[0]):
        raise ValueError(f"camera model is {camera.width}x{camera.height} but the image is "
                         f"{rgb.shape[1]}x{rgb.shape[0]}")


_KERNELS: dict[int, np.ndarray] = {}


def _kernel(size: int) -> np.ndarray | None:
    import cv2

    if size <= 1:
        return None
    if size not in _KERNELS:
        _KERNELS[size] = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size))
    return _KERNELS[size]


def colour_mask(hsv: np.ndarray, rng: HsvRange, kernel: np.ndarray | None) -> np.ndarray:
    """Binary mask (0/255) of one colour range after opening (specks) and closing (holes)."""
    import cv2

    lo, hi = rng.lo, rng.hi
    if lo[0] <= hi[0]:
        mask = cv2.inRange(hsv, lo, hi)
    else:                                   # hue range wraps through red (H 179 -> 0)
        mask = cv2.inRange(hsv, lo, (179, hi[1], hi[2])) | cv2.inRange(hsv, (0, lo[1], lo[2]), hi)
    if kernel is not None:
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, kernel)
        mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, kernel)
    return mask


def _blobs(hsv: np.ndarray, depth: np.ndarray, cam: CameraModel, cfg: DetectorConfig, rng: HsvRange,
           name: str, kernel: np.ndarray | None) -> list[Blob]:
    import cv2

    mask = colour_mask(hsv, rng, kernel)
    out = []
    for x, y, sub, area, v_c in _components(mask, cfg.min_area_px):
        blob = _measure(sub, x, y, v_c, depth, cam, cfg, name, area)
        if blob is None or blob.mixed:
            parts = _split_by_depth(sub, x, y, depth, cam, cfg, name)
            if parts or blob is None:
                out.extend(parts)
                continue
        out.append(blob)
    return out


def _components(mask: np.ndarray, min_area: int) -> list[tuple[int, int, np.ndarray, int, float]]:
    """Connected blobs of a 0/255 mask as (x, y, boolean bbox-sized mask, area, centroid row).

    External contours and their bounding boxes cost far less than labelling the whole frame when, as
    here, the mask is nearly empty.
    """
    import cv2

    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    out = []
    for c in contours:
        x, y, w, h = cv2.boundingRect(c)
        if w * h < min_area:
            continue
        own = np.zeros((h, w), np.uint8)
        cv2.drawContours(own, [c], -1, 255, thickness=-1, offset=(-x, -y))
        sub = (own > 0) & (mask[y:y + h, x:x + w] > 0)
        area = int(np.count_nonzero(sub))
        if area < min_area:
            continue
        v_c = y + float(np.nonzero(sub)[0].mean())
        out.append((x, y, sub, area, v_c))
    return out


def _split_by_depth(sub: np.ndarray, x0: int, y0: int, depth: np.ndarray, cam: CameraModel,
                    cfg: DetectorConfig, name: str) -> list[Blob]:
    """A marker touching a same-coloured object in the image (a blue box behind it, a blue pole
    beside it): cut the merged blob into depth layers and measure each layer's components alone."""
    import cv2

    h, w = sub.shape
    d = depth[y0:y0 + h, x0:x0 + w]
    vals = np.sort(d[sub & (d > 0)])
    if vals.size < 2 * cfg.min_depth_px:
        return []
    tol = np.maximum(0.06, 0.008 * vals[1:] ** 2)
    cuts = np.nonzero(np.diff(vals) > tol)[0]
    if cuts.size == 0:
        return []
    bounds = np.split(vals, cuts + 1)
    out = []
    for layer in bounds:
        if layer.size < cfg.min_depth_px:
            continue
        pad = max(0.03, 0.004 * float(layer[-1]) ** 2)
        lm = (sub & (d >= layer[0] - pad) & (d <= layer[-1] + pad)).view(np.uint8) * 255
        lm = cv2.morphologyEx(lm, cv2.MORPH_CLOSE, _kernel(3))      # refill dropouts
        lm &= sub.view(np.uint8) * 255
        for x, y, piece, area, v_c in _components(lm, cfg.min_area_px):
            blob = _measure(piece, x0 + x, y0 + y, y0 + v_c, depth, cam, cfg, name, area)
            if blob is not None and not blob.mixed:
                out.append(blob)
    return out


def _measure(sub: np.ndarray, x0: int, y0: int, v_c: float, depth: np.ndarray, cam: CameraModel,
             cfg: DetectorConfig, name: str, area: int) -> Blob | None:
    """Axis position of a cylinder from its mask (bbox-sized boolean ``sub`` at x0, y0) and the depth.

    Returns a bearing-only blob (``ranged`` False, NaN position) when neither the depth image nor the
    silhouette size gives its range: its partner cylinder may still place it (``_place_on_circle``).
    """
    h, w = sub.shape
    r = cfg.radius_m
    rows = sub.any(axis=1)
    row_idx = np.nonzero(rows)[0]
    left = np.argmax(sub[rows], axis=1)
    right = w - 1 - np.argmax(sub[rows][:, ::-1], axis=1)
    u_left = x0 + float(np.median(left)) - 0.5           # silhouette edges between pixel centres
    u_right = x0 + float(np.median(right)) + 0.5
    phi_l = math.atan((u_left - cam.cx) / cam.fx)
    phi_r = math.atan((u_right - cam.cx) / cam.fx)
    phi = (phi_l + phi_r) / 2
    half = (phi_r - phi_l) / 2
    top, bottom = y0 + int(row_idx[0]), y0 + int(row_idx[-1])
    clipped = top <= 0 or bottom >= cam.height - 1
    sides = _neighbour_depths(depth, cam, y0, h, u_left, u_right)

    dsub = depth[y0:y0 + h, x0:x0 + w]
    sel = sub & (dsub > 0)
    vv, uu = np.nonzero(sel)
    z = dsub[vv, uu].astype(np.float64)
    tau = (uu + x0 - cam.cx) / cam.fx
    rho = z * np.sqrt(1.0 + tau * tau)                  # range in the horizontal plane
    ang = np.arctan(tau)

    base = dict(colour=name, area_px=area, bbox=(x0, y0, w, h), v=v_c, mask=sub, phi_left=phi_l, phi_right=phi_r,
                height_px=bottom - top + 1, clipped=clipped, sides=sides)
    rng_m, sig, used, frac = _range_from_depth(rho, ang, phi, r)
    from_size = False
    if rng_m is None:                           # no depth (closer than the sensor's minimum, shadow)
        rng_m = _range_from_size(half, bottom - top + 1, clipped, cam, cfg)
        if rng_m is None or _occluded_sides(sides, rng_m, cfg):
            return Blob(u=cam.cx + cam.fx * math.tan(phi), x_m=math.nan, z_m=math.nan, range_m=math.nan,
                        range_sigma_m=math.inf, cross_sigma_m=math.inf, top_y_m=None, depth_px=0,
                        from_size=False, occluded="", ranged=False, **base)
        sig, used, from_size = rng_m * (cfg.pixel_sigma_px / cam.fx) / half * 1.4, 0, True

    occluded = _occluded_sides(sides, rng_m, cfg)
    expected_half = math.asin(min(1.0, r / rng_m))
    if occluded in ("left", "right") and half < 0.9 * expected_half:
        phi = phi_r - expected_half if occluded == "left" else phi_l + expected_half
        again = _range_from_depth(rho, ang, phi, r)
        if again[0] is not None:
            rng_m, sig, used, frac = again
    if not _size_plausible(w, h, area, rng_m, cam, cfg):
        return None                              # far bigger than a marker at this range: not one
    top_y = None if top <= 0 else (top - 0.5 - cam.cy) * (rng_m - r) * math.cos(phi) / cam.fy
    cross = rng_m * cfg.pixel_sigma_px / cam.fx * (2.0 if occluded else 1.0)
    return Blob(u=cam.cx + cam.fx * math.tan(phi), x_m=rng_m * math.sin(phi), z_m=rng_m * math.cos(phi),
                range_m=rng_m, range_sigma_m=sig, cross_sigma_m=cross, top_y_m=top_y, depth_px=used,
                from_size=from_size, occluded=occluded, ranged=True, mixed=frac < 0.7, **base)


def _size_plausible(w: int, h: int, area: int, rng_m: float, cam: CameraModel, cfg: DetectorConfig) -> bool:
    exp_w = 2 * cam.fx * cfg.radius_m / rng_m
    exp_h = cam.fy * cfg.height_m / max(rng_m - cfg.radius_m, 0.05)
    # a partly hidden cylinder is narrower, never wider: width is the sharp test, height a loose one
    return (w <= 1.25 * exp_w + 2 and h <= cfg.max_size_ratio * exp_h + 4
            and area <= cfg.max_size_ratio * exp_w * exp_h + 30)


def _neighbour_depths(depth: np.ndarray, cam: CameraModel, y0: int, h: int, u_left: float,
                      u_right: float) -> tuple[float, float]:
    """Median depth just beside each silhouette edge: -1 at the image border, NaN without readings."""
    out = []
    for u_edge, step in ((u_left, -1), (u_right, 1)):
        if u_edge <= 0.5 or u_edge >= cam.width - 1.5:
            out.append(-1.0)
            continue
        a, b = (int(u_edge - 5), int(u_edge - 1)) if step < 0 else (int(u_edge + 1.5), int(u_edge + 5.5))
        a, b = max(a, 0), min(b, cam.width)
        strip = depth[y0:y0 + h, a:b]
        vals = strip[strip > 0]
        out.append(float(np.median(vals)) if vals.size >= 3 else math.nan)
    return out[0], out[1]


def _occluded_sides(sides: tuple[float, float], rng_m: float, cfg: DetectorConfig) -> str:
    """Which silhouette edges are hidden: by the image border (-1) or by something nearer beside them."""
    limit = rng_m - cfg.radius_m - cfg.occlusion_step_m
    hidden = [name for name, z in zip(("left", "right"), sides) if z == -1.0 or (z == z and z < limit)]
    return "both" if len(hidden) == 2 else (hidden[0] if hidden else "")


def _range_from_size(half: float, height_px: int, clipped: bool, cam: CameraModel,
                     cfg: DetectorConfig) -> float | None:
    """Range from the silhouette's angular width, 2 asin(r / R), if its height in pixels agrees.

    The height check rejects silhouettes narrowed by something in front that has no depth reading
    either (an occluder closer than the sensor's minimum range).
    """
    if half <= 0 or clipped:
        return None
    rng_w = cfg.radius_m / math.sin(min(half, 1.0))
    if rng_w > cfg.max_size_range_m:
        return None                 # a pixel of width is more than ~4 % of range beyond this
    expected_px = cam.fy * cfg.height_m / (rng_w - cfg.radius_m)
    # the robot's top plate may hide the foot (shorter), but a narrowed silhouette looks too tall
    return rng_w if 0.6 * expected_px - 2 <= height_px <= 1.12 * expected_px + 3 else None


def _range_from_depth(rho: np.ndarray, ang: np.ndarray, phi: float, r: float
                      ) -> tuple[float | None, float, int, float]:
    """Axis range from surface ranges: R = rho cos(a) + sqrt(r^2 - rho^2 sin^2(a)), robust mean."""
    if rho.size == 0:
        return None, 0.0, 0, 1.0
    a = ang - phi
    s = rho * np.sin(a)
    keep = np.abs(s) < 0.8 * r                  # the rims are steep: misregistration and mixed pixels
    if np.count_nonzero(keep) < 6:
        return None, 0.0, 0, 1.0
    est = rho[keep] * np.cos(a[keep]) + np.sqrt(r * r - s[keep] ** 2)
    med = float(np.median(est))
    mad = float(np.median(np.abs(est - med))) * 1.4826
    tol = max(3.0 * mad, 0.01 + 0.004 * med * med)
    inl = est[np.abs(est - med) <= tol]
    if inl.size < 6:
        return None, 0.0, 0, 1.0
    mean = float(inl.mean())
    # neighbouring depth pixels share noise (block matching): count about one independent sample per 4
    sig = float(inl.std()) / math.sqrt(max(1.0, inl.size / 4.0)) + 0.0005 * mean
    return mean, sig, int(inl.size), inl.size / est.size


def _pose(f: Blob, r: Blob, spacing: float, cam: CameraModel, cfg: DetectorConfig) -> Detection:
    mx, mz = (f.x_m + r.x_m) / 2, (f.z_m + r.z_m) / 2
    yaw = _fit_heading(f, r, cfg.spacing_m)
    conf = math.exp(-((spacing - cfg.spacing_m) / 0.02) ** 2 / 2)
    conf *= 0.6 if (f.from_size or r.from_size or f.placed or r.placed) else 1.0
    conf *= 0.8 if (f.occluded or r.occluded) else 1.0
    conf *= min(1.0, (f.area_px + r.area_px) / 120.0)
    return Detection(
        angle_deg=math.degrees(math.atan2(mx, mz)), depth_m=mz, yaw_deg=yaw, x_m=mx, z_m=mz,
        front_px=(f.u, f.v), rear_px=(r.u, r.v), spacing_m=spacing, confidence=round(conf, 3),
        front=f, rear=r)


_GRID = np.linspace(-math.pi, math.pi, 721)[:-1]


def _fit_heading(f: Blob, r: Blob, length: float) -> float:
    """Heading on the circle |front - rear| = length closest (Mahalanobis) to the measured difference.

    Each axis position is uncertain mostly along its viewing ray (depth noise) and little across it
    (pixel edges), so the fit trusts the lateral offset between the cylinders more than their depth step.
    """
    hx, hz = f.x_m - r.x_m, f.z_m - r.z_m
    cov = np.zeros((2, 2))
    for b in (f, r):
        n = math.hypot(b.x_m, b.z_m)
        d = np.array([b.x_m / n, b.z_m / n])
        e = np.array([d[1], -d[0]])
        cov += b.range_sigma_m ** 2 * np.outer(d, d) + b.cross_sigma_m ** 2 * np.outer(e, e)
    inv = np.linalg.inv(cov + np.eye(2) * 1e-10)
    ex = length * np.sin(_GRID) - hx
    ez = length * np.cos(_GRID) - hz
    cost = inv[0, 0] * ex * ex + 2 * inv[0, 1] * ex * ez + inv[1, 1] * ez * ez
    k = int(np.argmin(cost))
    c0, c1, c2 = cost[k - 1], cost[k], cost[(k + 1) % cost.size]
    den = c0 - 2 * c1 + c2
    step = (_GRID[1] - _GRID[0]) * (0.5 * (c0 - c2) / den if den > 0 else 0.0)
    yaw = math.degrees(_GRID[k] + step)
    return (yaw + 180.0) % 360.0 - 180.0
