"""Simulated seconds per wall second of the embedded simulator, for 2, 10 and 50 robots.

Every robot rotates slowly (a motion is always in progress) in an arena with a few obstacles; each
carries a Kinect-like camera taking 640x480 RGB-D frames at 10 Hz simulated. A frame is a snapshot of
the scene whose pixels are rendered when someone reads them (``camera.DeferredFrame``), so two camera
columns are measured: listeners that read every frame's pixels (every frame rendered, what a
consumer processing each frame costs) and listeners that keep the latest frame unread (frames
delivered at 10 Hz, pixels only on demand). Frames actually rendered are counted, not assumed.
Targets (issue 5): >= 20x real time for 2 robots, >= 1x for 50, with cameras.
"""
from __future__ import annotations

import math
import time

from robot_bridge.sim.world import Obstacle, World

TARGETS = {2: 20.0, 10: None, 50: 1.0}


def build(robots: int, cameras: bool, seed: int = 0, read: bool = True) -> World:
    """``robots`` robots on a grid, all rotating at 20 deg/s; with ``cameras`` each has a listener that
    reads every frame's pixels (``read``) or keeps the latest frame unread."""
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
            if read:
                world.subscribe_camera(name, lambda frame, name=name: latest.__setitem__(name, frame.rgb))
            else:
                world.subscribe_camera(name, lambda frame, name=name: latest.__setitem__(name, frame))
        world.command(name, "rotate", (20.0,))
    return world


def measure(robots: int, cameras: bool, sim_seconds: float, read: bool = True) -> tuple[float, int, float]:
    """(simulated seconds per wall second, frames rendered, frames delivered) stepping flat out."""
    from robot_bridge.sim.camera import frames_rendered

    world = build(robots, cameras, read=read)
    world.run(0.1)                      # warm-up: renderer constants, noise banks
    delivered = [0]
    if cameras:
        for name in world.robots:
            world.subscribe_camera(name, lambda frame: delivered.__setitem__(0, delivered[0] + 1))
    rendered0, started, t0 = frames_rendered(), time.perf_counter(), world.time
    world.run(sim_seconds)
    wall = time.perf_counter() - started
    return (world.time - t0) / wall, frames_rendered() - rendered0, delivered[0] / wall


def run(quick: bool) -> str:
    import cv2

    sizes = (2, 10) if quick else (2, 10, 50)
    duration = {2: 4.0, 10: 2.0, 50: 1.0} if quick else {2: 20.0, 10: 5.0, 50: 2.0}
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        lines = [f"{'robots':>6} | {'physics only':>12} | {'cams, every frame read':>30} | "
                 f"{'cams, frames kept unread':>26} | {'target':>7} | met (read / unread)",
                 "-" * 118]
        for n in sizes:
            bare, _, _ = measure(n, False, duration[n] * 5)
            seen, made, _ = measure(n, True, duration[n], read=True)
            lazy, lazy_made, delivered = measure(n, True, duration[n], read=False)
            made_rate = made * seen / duration[n]          # frames rendered per wall second
            target = TARGETS.get(n)
            verdict = "-" if target is None else " / ".join("yes" if x >= target else "NO" for x in (seen, lazy))
            goal = f">= {target:g}x" if target else "-"
            lines.append(f"{n:>6} | {bare:>11.1f}x | {seen:>7.2f}x {made:>6d} fr {made_rate:>6.0f} fr/s | "
                         f"{lazy:>7.2f}x {lazy_made:>3d} fr {delivered:>5.0f} fr/s | {goal:>7} | {verdict}")
    finally:
        cv2.setNumThreads(threads)
    lines.append("(simulated seconds per wall second, dt = 0.02 s; 'fr' = 640x480 RGB-D frames actually rendered "
                 "in the run, 'fr/s' = frames rendered (read) or delivered (unread) per wall second; one OpenCV "
                 "thread)")
    return "\n".join(lines)


if __name__ == "__main__":
    print(run(quick=False))
