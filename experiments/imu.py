"""``faultmas experiment imu``: the TU Graz use case (seed paper, section VI), reproduced and measured.

A Kobuki-like robot drives round six waypoints; its odometry fuses the encoders with the IMU's
rotation. An IMU fault starts at a random time; one movement observer compares IMU and wheel yaw
rates, the diagnoser blames the IMU, and the rule ``~movement(imu,wheel_odom)`` + ``imu`` in PosAb
sets ``use_imu`` of the odometry to false. Three odometries of the same run (encoders only, always
IMU, diagnosis-switched) are compared against ground truth, as the paper compares them against
OptiTrack. See docs/experiments.md for the model, the noise figures and the measured table.
"""
from __future__ import annotations

import argparse
import json
import sys

FAULTS = ("imu_stuck", "imu_over", "imu_zero_after_rotating")
FAULT_WINDOW = (1.0 / 6.0, 2.0 / 3.0)
"""The fault starts at a uniformly random time within this part of the run (30-120 s of 180 s)."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--fault", default="all", choices=(*FAULTS, "none", "all"),
                        help="which IMU fault; 'none' runs fault-free; 'all' (default) the three and fault-free")
    parser.add_argument("--runs", type=int, default=None,
                        help="runs per fault (default 20 in the embedded simulator, 1 on ros2)")
    parser.add_argument("--seed", type=int, default=0, help="first seed; run i uses seed + i (default 0)")
    parser.add_argument("--duration", type=float, default=180.0,
                        help="seconds of driving per run (default 180: the paper's three minutes)")
    parser.add_argument("--bridge", default="sim", choices=("sim", "ros2"),
                        help="sim: embedded simulator, faster than real time (default); ros2: the real rclpy "
                             "nodes in other processes, in real time")
    parser.add_argument("--domain-id", type=int, default=None, help="ROS_DOMAIN_ID for --bridge ros2")
    parser.add_argument("--plot", metavar="OUT.png", help="draw ground truth and the three odometries of "
                        "the first run of each fault, with the moment of the switch")
    parser.add_argument("--json", action="store_true", help="print the results as one JSON object")


def fault_time(seed: int, duration: float) -> float:
    """When run ``seed``'s fault starts (s): uniform within ``FAULT_WINDOW`` of the run."""
    import numpy as np
    low, high = FAULT_WINDOW
    return float(np.random.default_rng([seed, 11]).uniform(low * duration, high * duration))


def main(args: argparse.Namespace) -> int:
    from experiments import imu_report

    if args.duration <= 10.0:
        print("error: --duration must be more than 10 s (the robot needs time to drive)", file=sys.stderr)
        return 2
    runs = args.runs if args.runs is not None else (20 if args.bridge == "sim" else 1)
    if runs < 1:
        print("error: --runs must be at least 1", file=sys.stderr)
        return 2
    faults = (*FAULTS, "none") if args.fault == "all" else (args.fault,)
    summaries, firsts = [], []
    try:
        run_one = _runner(args)
        for fault in faults:
            results = []
            for i in range(runs):
                seed = args.seed + i
                result = run_one(fault, fault_time(seed, args.duration), seed)
                results.append(result)
                _progress(fault, i, runs, result)
            summaries.append(imu_report.summarize(fault, results))
            firsts.append(results[0])
    except (RuntimeError, ImportError) as exc:      # ROS 2 missing, a node that died: say so, no traceback
        print(f"error: experiment imu on {args.bridge}: {exc}", file=sys.stderr)
        return 1
    settings = {"bridge": args.bridge, "runs": runs, "seed": args.seed, "duration_s": args.duration,
                "fault_window_s": [FAULT_WINDOW[0] * args.duration, FAULT_WINDOW[1] * args.duration]}
    if args.json:
        print(json.dumps(imu_report.to_json(summaries, settings), indent=2))
    else:
        print(f"faultmas experiment imu: {runs} run(s) of {args.duration:g} s per fault on {args.bridge}, "
              f"seeds {args.seed}..{args.seed + runs - 1}, fault at a random time in "
              f"{settings['fault_window_s'][0]:.0f}-{settings['fault_window_s'][1]:.0f} s; "
              "median [p25, p75] over the runs\n")
        print(imu_report.table(summaries))
    if args.plot:
        imu_report.plot(firsts, args.plot)
        print(f"plot: {args.plot}", file=sys.stderr)
    return 0


def _runner(args: argparse.Namespace):
    if args.bridge == "sim":
        from experiments import imu_sim
        return lambda fault, start, seed: imu_sim.run(fault, start, seed, args.duration)
    from experiments import imu_ros2
    return lambda fault, start, seed: imu_ros2.run(fault, start, seed, args.duration, domain_id=args.domain_id)


def _progress(fault: str, index: int, runs: int, result) -> None:
    if result.fault_time is None:
        what = "fault-free: " + ("FALSE SWITCH at %.1f s" % result.switch_time if result.switch_time is not None
                                 else "no switch")
    elif result.switch_time is None:
        what = f"fault at {result.fault_time:.1f} s, never switched"
    else:
        what = f"fault at {result.fault_time:.1f} s, switched at {result.switch_time:.1f} s"
    print(f"imu: {fault} run {index + 1}/{runs} (seed {result.seed}): {what}; mean error "
          f"always IMU {result.mean_error('always_imu'):.2f} m, switched {result.mean_error('switched'):.2f} m",
          file=sys.stderr, flush=True)
