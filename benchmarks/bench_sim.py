"""Simulated seconds per wall second of the embedded simulator, for 2, 10 and 50 robots.

Every robot rotates slowly (a motion is always in progress) in an arena with a few obstacles; each
carries a Kinect-like camera taking 640x480 RGB-D frames at 10 Hz simulated. A frame is a snapshot of
the scene whose pixels are rendered when someone reads them (``camera.DeferredFrame``). The target
is measured with EVERY frame rendered, as a bridge that runs detection on each frame needs: its
listeners subscribe with ``reads_pixels=True``, so the frames due at the same step are rendered
together, shared with render worker processes (``camera.render_all``, ``render_processes``). Frames rendered are
counted, not assumed, and must equal the frames due. For comparison: listeners reading the pixels in
their callback, one frame after the other, and listeners that keep the latest frame unread (frames
delivered at 10 Hz, pixels only on demand).
Targets (issue 5): >= 20x real time for 2 robots, >= 1x for 50, every frame rendered.
"""
from __future__ import annotations

import math
import os
import time

from robot_bridge.sim.world import Obstacle, World

TARGETS = {2: 20.0, 10: None, 50: 1.0}
MODES = ("parallel", "serial", "unread")
"""How listeners treat frames: read every frame's pixels (rendered side by side, or one after the
other in the listeners), or keep the latest frame unread."""


def build(robots: int, cameras: bool, seed: int = 0, mode: str = "parallel") -> World:
    """``robots`` robots on a grid, all rotating at 20 deg/s; with ``cameras`` each has a listener that
    treats frames as ``mode`` says (see ``MODES``)."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
    side = math.ceil(math.sqrt(robots))
    half = side * 0.6 + 1.0
    world = World(seed=seed, arena=(-half, -half, half, half),
                  obstacles=(Obstacle(half - 0.5, 0.0), Obstacle(0.0, half - 0.5, rgb=(200, 30, 35)),
                             Obstacle(-half + 0.5, -half + 0.5, radius=0.3, rgb=(160, 118, 70))))
    latest: dict[str, object] = {}
    for i in range(robots):
        name = f"r{i}"
        x, y = (i % side) * 1.2 - half + 1.2, (i // side) * 1.2 - half + 1.2
        world.add_robot(name, x=x, y=y, yaw_deg=(37 * i) % 360, camera=cameras)
        if cameras:
            if mode == "unread":
                world.subscribe_camera(name, lambda frame, name=name: latest.__setitem__(name, frame))
            else:
                world.subscribe_camera(name, lambda frame, name=name: latest.__setitem__(name, frame.rgb),
                                       reads_pixels=mode == "parallel")
        world.command(name, "rotate", (20.0,))
    return world


def measure(robots: int, cameras: bool, sim_seconds: float, mode: str = "parallel"
            ) -> tuple[float, int, int, float]:
    """(simulated seconds per wall second, frames rendered, frames due, CPU seconds of this process and
    of its render workers) stepping flat out."""
    from robot_bridge.sim.camera import frames_rendered
    from robot_bridge.sim.render_processes import shared_pool

    world = build(robots, cameras, mode=mode)
    world.run(0.1)                      # warm-up: renderer constants, noise banks, render threads
    pool = shared_pool() if cameras and mode == "parallel" else None
    if pool is not None:
        pool.wait_ready(60.0)           # render processes start once, in the first run
    workers_cpu = pool.worker_cpu_seconds if pool is not None else 0.0
    due = [0]
    if cameras:
        for name in world.robots:
            world.subscribe_camera(name, lambda frame: due.__setitem__(0, due[0] + 1))
    rendered0, started, cpu, t0 = frames_rendered(), time.perf_counter(), time.process_time(), world.time
    world.run(sim_seconds)
    wall = time.perf_counter() - started
    workers_cpu = (pool.worker_cpu_seconds if pool is not None else 0.0) - workers_cpu
    return (world.time - t0) / wall, frames_rendered() - rendered0, due[0], time.process_time() - cpu + workers_cpu


def run(quick: bool) -> str:
    import cv2

    from robot_bridge.sim.camera import objects as camera

    sizes = (2, 10) if quick else (2, 10, 50)
    duration = {2: 4.0, 10: 2.0, 50: 1.0} if quick else {2: 20.0, 10: 5.0, 50: 2.0}
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        lines = [f"{'robots':>6} | {'physics':>8} | {'EVERY FRAME RENDERED, reads_pixels':>45} | "
                 f"{'every frame, in callback':>24} | {'frames kept unread':>18} | {'target':>7} | met",
                 "-" * 132]
        for n in sizes:
            bare, _, _, _ = measure(n, False, duration[n] * 5)
            fast, made, due, cpu = measure(n, True, duration[n], "parallel")
            serial, serial_made, _, _ = measure(n, True, duration[n], "serial")
            lazy, lazy_made, _, _ = measure(n, True, duration[n], "unread")
            target = TARGETS.get(n)
            verdict = "-" if target is None else "yes" if fast >= target and made == due else "NO"
            goal = f">= {target:g}x" if target else "-"
            rate = made * fast / duration[n]
            lines.append(f"{n:>6} | {bare:>7.1f}x | {fast:>7.2f}x {made:>5d}/{due:<5d} fr {rate:>5.0f} fr/s "
                         f"{1e3 * cpu / max(made, 1):>4.1f} ms CPU/fr | {serial:>7.2f}x "
                         f"{serial * serial_made / duration[n]:>5.0f} fr/s | {lazy:>7.2f}x {lazy_made:>3d} fr | "
                         f"{goal:>7} | {verdict}")
    finally:
        cv2.setNumThreads(threads)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines.append(f"(simulated seconds per wall second, dt = 0.02 s, 10 Hz cameras; 'fr' = 640x480 RGB-D frames "
                 f"rendered / due in the run, 'fr/s' = frames rendered per wall second, 'ms CPU/fr' = CPU time of this "
                 f"process (physics included) and of its render workers per frame rendered, less sensitive than wall time to other loads on the "
                 f"machine; reads_pixels: {_renderers()}; one OpenCV thread each; cylinders drawn by "
                 f"{'the compiled loop' if camera._ZBUFFER is not None else 'numpy (compiled loop not built)'}; "
                 f"'met' judges the every-frame column; machine load average (1 min) at the end: {load:.1f} "
                 f"on {os.cpu_count()} cores)")
    return "\n".join(lines)


def _renderers() -> str:
    from robot_bridge.sim.camera import render_threads
    from robot_bridge.sim.render_processes import ENV_WORKERS, shared_pool

    pool = shared_pool()
    if pool is not None and pool.broken is None:
        return (f"this process and {pool.size} render worker process(es) ({ENV_WORKERS}), "
                f"{pool.frames_by_workers} frames rendered by the workers")
    why = f" ({pool.broken})" if pool is not None else f" ({ENV_WORKERS}=0 or one core)"
    return f"no render processes{why}, up to {render_threads()} render threads"


if __name__ == "__main__":
    print(run(quick=False))
