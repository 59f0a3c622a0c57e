"""Simulated seconds per wall second of the embedded simulator, for 2, 10 and 50 robots.

Every robot rotates slowly (a motion is always in progress) in an arena with a few obstacles; each
carries a Kinect-like camera rendering 640x480 RGB-D frames at 10 Hz simulated for a listener that
keeps the latest frame. Columns: physics only (cameras off), then with the cameras. Targets (issue 5):
>= 20x real time for 2 robots, >= 1x for 50, with cameras.
"""
from __future__ import annotations

import math
import time

from robot_bridge.sim.world import Obstacle, World

TARGETS = {2: 20.0, 10: None, 50: 1.0}


def build(robots: int, cameras: bool, seed: int = 0) -> World:
    """``robots`` robots on a grid, all rotating at 20 deg/s; cameras listened to if ``cameras``."""
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
            world.subscribe_camera(name, lambda frame, name=name: latest.__setitem__(name, frame))
        world.command(name, "rotate", (20.0,))
    return world


def measure(robots: int, cameras: bool, sim_seconds: float) -> float:
    """Simulated seconds per wall second, stepping flat out."""
    world = build(robots, cameras)
    world.run(0.1)                      # warm-up: renderer constants, noise banks
    started, t0 = time.perf_counter(), world.time
    world.run(sim_seconds)
    return (world.time - t0) / (time.perf_counter() - started)


def run(quick: bool) -> str:
    sizes = (2, 10) if quick else (2, 10, 50)
    duration = {2: 4.0, 10: 2.0, 50: 1.0} if quick else {2: 20.0, 10: 5.0, 50: 2.0}
    lines = [f"{'robots':>6} | {'physics only':>14} | {'cameras 10 Hz':>14} | {'target':>7} | met",
             "-" * 60]
    for n in sizes:
        bare = measure(n, False, duration[n] * 5)
        seen = measure(n, True, duration[n])
        target = TARGETS.get(n)
        verdict = "-" if target is None else ("yes" if seen >= target else "NO")
        goal = f">= {target:g}x" if target else "-"
        lines.append(f"{n:>6} | {bare:>13.1f}x | {seen:>13.2f}x | {goal:>7} | {verdict}")
    lines.append("(simulated seconds per wall second; dt = 0.02 s; 640x480 RGB-D per camera frame)")
    return "\n".join(lines)


if __name__ == "__main__":
    print(run(quick=False))
