"""Perception benchmark: the detector on rendered RGB-D scenes with ground truth from the renderer.

Scenes (``robot_bridge.sim.render_scenes.random_scene``): target depth 0.8-4 m, bearing +-27 deg, any
heading, illumination gain 0.5-1.5, clutter, a lone orange/blue cylinder in 30 %, an occluder on the
line of sight in 30 %, a second robot in 10 %, Kinect-like depth (noise, 1/8 px disparity steps,
dropouts, projector shadows, 1 px registration error). "Visible" means both cylinders show >= 40 % of
their silhouette and >= 30 px. Times are CPU time of one thread (``cv2.setNumThreads(1)``). The table is
for seeds 50000..; the detection rate and far-off count are repeated on fresh seed ranges
(``FRESH_SEEDS``) that were not looked at while tuning the detector.
"""
from __future__ import annotations

import math
import time

import numpy as np

TARGETS = {"detection": 98.0, "far_off": 0, "angle_p95": 0.5, "depth_p95": 0.03, "yaw_p95": 5.0, "fps": 150.0}


def _wrap(deg: float) -> float:
    return (deg + 180.0) % 360.0 - 180.0


FRESH_SEEDS = (450_000, 550_000)     # never looked at while developing the detector: over-fitting check


def _scenes(first_seed: int, n: int) -> tuple[list[dict], float, float]:
    """Render and detect scenes ``first_seed .. first_seed + n - 1``: per-scene rows, render and detect
    CPU seconds (one OpenCV thread)."""
    import cv2

    from perception.detect import detect
    from robot_bridge.sim.camera import render_with_pixels, true_view
    from robot_bridge.sim.render_scenes import random_scene

    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        t_render = t_detect = 0.0
        rows = []
        for seed in range(first_seed, first_seed + n):
            s = random_scene(seed)
            t0 = time.process_time()
            rgb, depth, pixels = render_with_pixels(s.rig, s.camera_pose, s.robots, s.scene,
                                                    np.random.default_rng(seed))
            t1 = time.process_time()
            res = detect(rgb, depth, s.rig.camera)
            t2 = time.process_time()
            t_render += t1 - t0
            t_detect += t2 - t1
            truths = [true_view(s.rig, s.camera_pose, r) for r in s.robots]
            visible = pixels[0].both_visible()
            any_visible = any(p.both_visible() for p in pixels)
            err = None
            if res.found:
                d = res.detection
                errs = [(abs(d.angle_deg - t.angle_deg), abs(d.depth_m - t.depth_m), abs(_wrap(d.yaw_deg - t.yaw_deg)))
                        for t in truths]
                err = min(errs, key=lambda e: e[0] + 10 * e[1])
            rows.append(dict(visible=visible, any_visible=any_visible, err=err, z=truths[0].depth_m,
                             gain=s.scene.gain, occluder=s.occluder, reason=res.reason))
    finally:
        cv2.setNumThreads(threads)
    return rows, t_render, t_detect


def _rate(rows: list[dict]) -> tuple[float, int, int, int]:
    """(detection rate % on visible scenes, hits, visible, detections far off)."""
    vis = [r for r in rows if r["visible"]]
    hits = sum(1 for r in vis if r["err"] is not None)
    far = sum(1 for r in rows if r["err"] is not None and (r["err"][0] > 2.0 or r["err"][1] > 0.1))
    return 100.0 * hits / max(1, len(vis)), hits, len(vis), far


def run(quick: bool = False, first_seed: int = 50_000, n: int | None = None) -> str:
    n = n or (100 if quick else 600)
    rows, t_render, t_detect = _scenes(first_seed, n)
    vis = [r for r in rows if r["visible"]]
    hit = [r for r in vis if r["err"] is not None]
    found = [r for r in rows if r["err"] is not None]
    far_off = [r for r in found if r["err"][0] > 2.0 or r["err"][1] > 0.1]
    good = [r for r in found if r not in far_off]
    extra = [r for r in found if not r["any_visible"]]
    ang = np.array([r["err"][0] for r in good]) if good else np.zeros(1)
    dep = np.array([r["err"][1] for r in good]) if good else np.zeros(1)
    yaw = np.array([r["err"][2] for r in good]) if good else np.zeros(1)
    rate = 100.0 * len(hit) / max(1, len(vis))
    fps = n / t_detect if t_detect else math.inf
    fps_render = n / t_render if t_render else math.inf

    def ok(flag: bool) -> str:
        return "ok" if flag else "MISSED"

    def p(a: np.ndarray, q: float) -> float:
        return float(np.percentile(a, q))

    lines = [
        f"perception: {n} rendered scenes (640x480), {len(vis)} with both cylinders visible",
        f"{'metric':<44}{'value':>14}  {'target':>10}  status",
        f"{'detection rate, both cylinders visible':<44}{rate:>13.1f}%  {'>= 98%':>10}  {ok(rate >= 98.0)}",
        f"{'detections > 2 deg or > 0.1 m off':<44}{len(far_off):>14d}  {'0':>10}  {ok(not far_off)}",
        f"{'detections of robots below that bar':<44}{len(extra):>14d}  {'(info)':>10}",
        f"{'angle error p50 / p95 / max (deg)':<44}{p(ang, 50):>5.3f}/{p(ang, 95):.3f}/{ang.max():.2f}"
        f"  {'p95 < 0.5':>10}  {ok(p(ang, 95) < 0.5)}",
        f"{'depth error p50 / p95 / max (cm)':<44}{100 * p(dep, 50):>5.2f}/{100 * p(dep, 95):.2f}/{100 * dep.max():.1f}"
        f"  {'p95 < 3':>10}  {ok(p(dep, 95) < 0.03)}",
        f"{'heading error p50 / p95 / max (deg)':<44}{p(yaw, 50):>5.2f}/{p(yaw, 95):.2f}/{yaw.max():.1f}"
        f"  {'p95 < 5':>10}  {ok(p(yaw, 95) < 5.0)}",
        f"{'detect() frames/s, one thread (CPU time)':<44}{fps:>14.0f}  {'>= 150':>10}  {ok(fps >= 150)}",
        f"{'renderer RGB-D frames/s, one thread':<44}{fps_render:>14.0f}  {'(info)':>10}",
    ]
    # where the misses are: by distance and conditions
    lines.append("detection rate on visible scenes by condition:")
    groups = [("0.8-1.5 m", lambda r: r["z"] < 1.5), ("1.5-2.5 m", lambda r: 1.5 <= r["z"] < 2.5),
              ("2.5-4 m", lambda r: r["z"] >= 2.5), ("gain < 0.75", lambda r: r["gain"] < 0.75),
              ("gain > 1.25", lambda r: r["gain"] > 1.25), ("occluder", lambda r: r["occluder"])]
    for name, pred in groups:
        g = [r for r in vis if pred(r)]
        h = sum(1 for r in g if r["err"] is not None)
        lines.append(f"  {name:<14}{h:>5d}/{len(g):<5d} {100.0 * h / max(1, len(g)):6.1f}%")
    reasons: dict[str, int] = {}
    for r in vis:
        if r["err"] is None:
            reasons[r["reason"]] = reasons.get(r["reason"], 0) + 1
    if reasons:
        lines.append("misses on visible scenes: " + ", ".join(f"{k} {v}" for k, v in sorted(reasons.items())))
    lines.append(f"the same on fresh seeds ({n} scenes each; the table above is seeds {first_seed}..):")
    for fresh in FRESH_SEEDS:
        f_rate, f_hits, f_vis, f_far = _rate(_scenes(fresh, n)[0])
        lines.append(f"  seeds {fresh}..{fresh + n - 1}: detection {f_hits}/{f_vis} = {f_rate:.1f}% "
                     f"({ok(f_rate >= 98.0)}), {f_far} far off ({ok(f_far == 0)})")
    return "\n".join(lines)


if __name__ == "__main__":
    import sys
    print(run(quick="--quick" in sys.argv))
