"""``make jason-tests``: run Jason 3.3.2's own AgentSpeak unit tests (unchanged, read in place) as a Jason
user would, ``faultmas mas run src/test/jason/unit_tests.mas2j`` from the suite's folder, and fail unless
every expected test ran and passed. Prints ``executed/passed``. Java Jason reports 468 executed, 468 passed.

    python -m tests.jason_suite [SUITE_DIR] [--processes] [--timeout S] [--expect N]

Nothing may be lost silently. Jason's test manager counts the results the testers send it and ends when
every tester that has *announced* itself is done; a tester that has not announced itself yet (created
late on a loaded machine) is not waited for, so a run can end with "#228 tests executed, #228 PASSED".
The run therefore passes only if the MAS exited with 0 (the manager stops with ``.stopMAS(0,1)`` when it
knows of a failure), the manager said "End of Jason unit tests: PASSED", at least ``--expect`` tests
executed, and every tester file with ``[test]`` plans showed up in the output; otherwise it says which.
"""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

SUMMARY = re.compile(r"#(\d+) tests executed, #(\d+) (?:passed|PASSED) and #(\d+) (?:failed|FAILED)")
PASSED_MARK = "End of Jason unit tests: PASSED"
TEST_LABEL = re.compile(r"@\w*\[[^\]]*\btest\b[^\]]*\]")
DEFAULT_DIR = Path(__file__).resolve().parents[3] / "shared" / "jason-unit-tests"
JAVA_EXECUTED = 468
"""Tests executed by Java Jason 3.3.2 on this suite (its README): fewer here means some went uncounted."""
TESTERS = Path("src/test/jason")
"""Where the test manager looks for tester files (``create_tester_agents`` in ``unit_tests.mas2j``), less
its ``inc/`` folder."""


@dataclass
class SuiteRun:
    """What one run of the suite printed and how it ended."""

    exit_code: int
    output: str
    executed: int = 0
    passed: int = 0
    failed: int = 0
    summary_found: bool = False
    problems: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems


def discover_testers(suite_dir: Path) -> list[str]:
    """The tester agents the test manager will create (one per ``.asl`` file under ``src/test/jason`` but
    outside ``inc/``, named after the file) that have at least one plan labelled ``test``."""
    root = suite_dir / TESTERS
    names = []
    for path in sorted(root.rglob("*.asl")):
        if (root / "inc") in path.parents:
            continue
        if TEST_LABEL.search(path.read_text(encoding="utf-8", errors="replace")):
            names.append(path.stem)
    return names


def judge(run: SuiteRun, testers: list[str], expect: int) -> SuiteRun:
    """Fill in ``run``'s counts and every reason it is not a complete, passed run."""
    found = SUMMARY.findall(run.output)
    if found:
        run.summary_found = True
        run.executed, run.passed, run.failed = (int(x) for x in found[-1])
    problems = run.problems
    if run.exit_code != 0:
        problems.append(f"the MAS exited with code {run.exit_code}"
                        + (" (cut by --timeout)" if run.exit_code == 124 else ""))
    if not run.summary_found:
        problems.append("the test manager printed no summary ('#N tests executed, ...')")
    elif PASSED_MARK not in run.output:
        problems.append(f"the test manager did not say '{PASSED_MARK}'")
    if run.summary_found and run.passed != run.executed:
        problems.append(f"{run.executed - run.passed} of {run.executed} executed tests did not pass")
    if run.executed < expect:
        problems.append(f"only {run.executed} tests executed, {expect} expected")
    printed = set(re.findall(r"^\[([^\]\s]+)\]", run.output, flags=re.MULTILINE))
    silent = [name for name in testers if name not in printed]
    if silent:
        problems.append(f"{len(silent)} of {len(testers)} tester agents printed nothing (never ran?): "
                        + ", ".join(silent))
    return run


def run_suite(suite_dir: Path, processes: bool = False, timeout: float = 700.0,
              expect: int = JAVA_EXECUTED) -> SuiteRun:
    """One run of the suite, judged."""
    cmd = [sys.executable, "-m", "agents", "mas", "run", "src/test/jason/unit_tests.mas2j", "--timeout", str(timeout)]
    if processes:
        cmd.append("--processes")
    try:
        proc = subprocess.run(cmd, cwd=suite_dir, capture_output=True, text=True, timeout=timeout + 60)
        run = SuiteRun(proc.returncode, proc.stdout + proc.stderr)
    except subprocess.TimeoutExpired as exc:
        out = exc.stdout.decode(errors="replace") if isinstance(exc.stdout, bytes) else (exc.stdout or "")
        run = SuiteRun(124, out)
        run.problems.append(f"the MAS did not end within {timeout + 60:.0f} s")
    return judge(run, discover_testers(suite_dir), expect)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.jason_suite", description=__doc__.splitlines()[0])
    parser.add_argument("suite_dir", nargs="?", default=str(DEFAULT_DIR))
    parser.add_argument("--processes", action="store_true", help="one OS process per agent")
    parser.add_argument("--timeout", type=float, default=700.0)
    parser.add_argument("--expect", type=int, default=JAVA_EXECUTED, metavar="N",
                        help=f"fail if fewer than N tests executed (default {JAVA_EXECUTED}, Java Jason's count)")
    parser.add_argument("--show", action="store_true", help="print the run's whole output")
    args = parser.parse_args(argv)
    suite = Path(args.suite_dir)
    if not (suite / "src/test/jason/unit_tests.mas2j").is_file():
        print(f"no Jason unit-test suite in {suite} (expected src/test/jason/unit_tests.mas2j)", file=sys.stderr)
        return 2
    started = time.monotonic()
    run = run_suite(suite, args.processes, args.timeout, args.expect)
    if args.show or not run.summary_found:
        print(run.output)
    else:  # the failed asserts, for whoever fixes them
        for line in run.output.splitlines():
            if "FAILED" in line or "NOT ACHIEVED" in line or "not launched" in line:
                print(line)
    load = os.getloadavg()[0] / (os.cpu_count() or 1)
    how = "--processes" if args.processes else "in one process"
    print(f"Jason unit tests ({how}): {run.executed}/{run.passed} (executed/passed), expected {args.expect} "
          f"(Java Jason: {JAVA_EXECUTED}/{JAVA_EXECUTED}); {time.monotonic() - started:.0f} s; load {load:.1f} per core")
    for problem in run.problems:
        print(f"FAILED: {problem}", file=sys.stderr)
    if run.problems and load > 1.5:
        # the scheduler and the timers keep the order an agent on a thread of its own sees (docs/language.md,
        # Timing), but deadlines that need a share of the CPU the machine does not give can still be missed
        print("(the machine is loaded: the suite's tests with deadlines in real time between agents, at (.at "
              "within 200 ms), send (a mock's answer within an ask's 200 ms), and, when the process gets the "
              "CPU only every second or so, queueplan and resume, may fail for that alone: docs/language.md, Timing)")
    return 0 if run.ok else 1


if __name__ == "__main__":
    sys.exit(main())
