"""One run of the IMU experiment in the embedded simulator: physics stepped directly, faster than real time.

No cameras, no threads: the loop steps a ``World`` with one miscalibrated Kobuki, steers it round the
waypoints, injects the fault at its time, feeds the gyro and wheel-odometry samples to the detection
pipeline (observers -> diagnoser -> rules) exactly as the topics would carry them (50 Hz each), and
samples the three odometries against ground truth.
"""
from __future__ import annotations

import math

import numpy as np

from experiments.imu_detection import Detection
from experiments.imu_result import RunResult, Sample
from experiments.waypoints import Route
from robot_bridge.sim import kobuki
from robot_bridge.sim.odometry_fusion import OdometryFusion
from robot_bridge.sim.world import World

ROBOT = "robot"
CONTROL_EVERY = 5
"""Steps (of 20 ms) between velocity commands: a 10 Hz controller."""
SAMPLE_EVERY = 5
"""Steps between error samples: 10 Hz."""


def run(fault: str, fault_time: float, seed: int, duration: float, detect: bool = True) -> RunResult:
    """Drive ``duration`` simulated seconds with ``fault`` from ``fault_time`` on (``none``: healthy).

    ``detect``: run the observers, diagnosis and rules (``False``: the three odometries only, the
    switched one never switches).
    """
    rng = np.random.default_rng([seed, 7])
    world = World(seed=seed, noise=True, log_interval=0.0, params=kobuki.miscalibrated(rng))
    world.add_robot(ROBOT)
    switches: list[float] = []

    def set_parameter(node: str, name: str, value: object) -> None:
        world.set_parameter(ROBOT, node, name, value)
        switches.append(world.time)

    detector = Detection(set_parameter) if detect else None
    always = OdometryFusion(use_imu=True)
    route = Route()
    dt = world.dt
    steps = round(duration / dt)
    samples: list[Sample] = []
    injected = fault == "none"
    for step in range(steps):
        now = step * dt
        if not injected and now >= fault_time:
            world.set_fault(ROBOT, fault)
            injected = True
        if step % CONTROL_EVERY == 0:
            x, y, yaw_deg = world.pose(ROBOT)
            world.drive(ROBOT, *route.command((x, y, math.radians(yaw_deg))))
        before = world.odometry(ROBOT)
        world.step()
        odom = world.odometry(ROBOT)
        rate = world.yaw_rate(ROBOT)
        always.step(odom.distance - before.distance, odom.rotation - before.rotation, rate * dt)
        t = (step + 1) * dt
        if detector is not None:
            detector.feed_imu(t, rate)
            detector.feed_wheels(t, odom.speed[1])
        if (step + 1) % SAMPLE_EVERY == 0:
            x, y, yaw_deg = world.pose(ROBOT)
            fused = world.fused_odometry(ROBOT)
            samples.append(Sample(t, (x, y), (odom.x, odom.y), (always.pose.x, always.pose.y),
                                  (fused.x, fused.y)))
    if detector is not None:
        detector.close()
    return RunResult(fault, fault_time if fault != "none" else None, seed, samples,
                     switches[0] if switches else None,
                     detector.cpu_seconds if detector is not None else 0.0, duration, route.reached)
