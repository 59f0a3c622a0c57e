"""The IMU experiment's speed targets: observers + diagnosis + rules <= 2 % of one core (issue 25), and
how much faster than real time the embedded simulator runs it.

CPU share = thread CPU time spent feeding the observers, judging, diagnosing and running the rules,
over the observed (simulated) time, with the robot's message rates (gyro and wheel odometry, 50 Hz
each). The table of errors is ``faultmas experiment imu``'s job, not this benchmark's.
"""
from __future__ import annotations

import time


def run(quick: bool = False) -> str:
    from experiments import imu, imu_sim

    duration = 60.0 if quick else 180.0
    runs = 1 if quick else 3
    lines = [f"{'fault':<26} {'runs':>4} {'CPU share (worst)':>18} {'target':>8} {'x real time':>12}"]
    for fault in (*imu.FAULTS, "none"):
        shares, wall = [], 0.0
        for seed in range(runs):
            started = time.perf_counter()
            result = imu_sim.run(fault, imu.fault_time(seed, duration), seed, duration)
            wall += time.perf_counter() - started
            shares.append(result.cpu_share)
        lines.append(f"{fault:<26} {runs:>4} {100 * max(shares):>17.3f}% {'<= 2 %':>8} "
                     f"{runs * duration / wall:>11.0f}x")
    return "\n".join(lines)
