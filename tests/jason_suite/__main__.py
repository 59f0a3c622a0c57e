"""``make jason-tests``: run Jason 3.3.2's own AgentSpeak unit tests (unchanged, read in place) as a Jason
user would, ``faultmas mas run src/test/jason/unit_tests.mas2j`` from the suite's folder, and fail unless
every executed test passed. Prints ``executed/passed``. Java Jason reports 468 executed, 468 passed.

    python -m tests.jason_suite [SUITE_DIR] [--processes] [--timeout S]
"""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import time
from pathlib import Path

SUMMARY = re.compile(r"#(\d+) tests executed, #(\d+) (?:passed|PASSED) and #(\d+) (?:failed|FAILED)")
DEFAULT_DIR = Path(__file__).resolve().parents[3] / "shared" / "jason-unit-tests"


def run_suite(suite_dir: Path, processes: bool = False, timeout: float = 700.0) -> tuple[int, int, int, str]:
    """(executed, passed, exit code, output) of one run of the suite."""
    cmd = [sys.executable, "-m", "agents", "mas", "run", "src/test/jason/unit_tests.mas2j", "--timeout", str(timeout)]
    if processes:
        cmd.append("--processes")
    proc = subprocess.run(cmd, cwd=suite_dir, capture_output=True, text=True, timeout=timeout + 60)
    output = proc.stdout + proc.stderr
    found = SUMMARY.findall(output)
    if not found:
        return 0, 0, proc.returncode, output
    executed, passed, _failed = (int(x) for x in found[-1])
    return executed, passed, proc.returncode, output


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.jason_suite", description=__doc__.splitlines()[0])
    parser.add_argument("suite_dir", nargs="?", default=str(DEFAULT_DIR))
    parser.add_argument("--processes", action="store_true", help="one OS process per agent")
    parser.add_argument("--timeout", type=float, default=700.0)
    parser.add_argument("--show", action="store_true", help="print the run's whole output")
    args = parser.parse_args(argv)
    suite = Path(args.suite_dir)
    if not (suite / "src/test/jason/unit_tests.mas2j").is_file():
        print(f"no Jason unit-test suite in {suite} (expected src/test/jason/unit_tests.mas2j)", file=sys.stderr)
        return 2
    started = time.monotonic()
    executed, passed, code, output = run_suite(suite, args.processes, args.timeout)
    if args.show or not executed:
        print(output)
    else:  # the failed asserts, for whoever fixes them
        for line in output.splitlines():
            if "FAILED" in line or "NOT ACHIEVED" in line or "not launched" in line:
                print(line)
    load = os.getloadavg()[0] / (os.cpu_count() or 1)
    how = "--processes" if args.processes else "in one process"
    print(f"Jason unit tests ({how}): {executed}/{passed} (executed/passed), Java Jason: 468/468; "
          f"{time.monotonic() - started:.0f} s; load {load:.1f} per core")
    if (executed != passed or not executed) and load > 1.5:
        # the scheduler and the timers keep the order an agent on a thread of its own sees (docs/language.md,
        # Timing), but deadlines that need a share of the CPU the machine does not give can still be missed
        print("(the machine is loaded: the suite's tests with deadlines in real time between agents, at (.at "
              "within 200 ms), send (a mock's answer within an ask's 200 ms), and, when the process gets the "
              "CPU only every second or so, queueplan and resume, may fail for that alone: docs/language.md, Timing)")
    return 0 if executed > 0 and executed == passed else 1


if __name__ == "__main__":
    sys.exit(main())
