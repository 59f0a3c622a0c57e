"""``make bench`` = ``python -m benchmarks [NAME ...]``: run the benchmark modules and print their tables.

Each module in BENCHMARKS has ``run(quick: bool) -> str`` returning a printable table. Timing lives here
and never in unit tests (machines are noisy): compare the columns of one run, not runs on different days.
"""
from __future__ import annotations

import argparse
import importlib
import sys
import time

BENCHMARKS: dict[str, str] = {
    "startup": "benchmarks.bench_startup",     # whole process: --help, hello world, vs baselines (issue 23)
    "asl": "benchmarks.bench_asl",
    "zenoh": "benchmarks.bench_zenoh",
    "agents": "benchmarks.bench_agents_zenoh",
    "diagnosis": "benchmarks.bench_diagnosis",
    "sim": "benchmarks.bench_sim",
    "perception": "benchmarks.bench_perception",
    "imu": "benchmarks.bench_imu",
    "observers": "benchmarks.bench_observers",
    "perfbugs": "benchmarks.bench_perfbugs",
    "inspect": "benchmarks.bench_inspect",
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", metavar="NAME",
                        help=f"benchmarks to run, among {', '.join(BENCHMARKS)} (default: all)")
    parser.add_argument("--quick", action="store_true", help="smaller sizes, for a smoke run")
    args = parser.parse_args(argv)
    unknown = [n for n in args.names if n not in BENCHMARKS]
    if unknown:
        parser.error(f"unknown benchmark {unknown[0]!r}; choose among {', '.join(BENCHMARKS)}")
    failed = 0
    for name in args.names or list(BENCHMARKS):
        try:
            module = importlib.import_module(BENCHMARKS[name])
        except ModuleNotFoundError as exc:
            if exc.name != BENCHMARKS[name]:
                raise
            print(f"== {name}: not built yet\n")
            continue
        started = time.perf_counter()
        print(f"== {name}", flush=True)
        try:
            print(module.run(quick=args.quick), flush=True)
        except Exception as exc:  # one broken benchmark must not hide the others' tables
            failed += 1
            print(f"benchmark {name} failed: {exc!r}", flush=True)
        print(f"({name}: {time.perf_counter() - started:.1f} s wall)\n", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
