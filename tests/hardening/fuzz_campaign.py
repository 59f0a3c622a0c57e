"""The long fuzz run of issue 22, by time rather than by count: every boundary of ``boundaries.BOUNDARIES`` in
turn gets ``--chunk`` mutated inputs (the strategy of ``test_fuzz_boundaries``, a fresh random seed each
round) until ``--minutes`` have passed. It prints a line per boundary and round with the totals so far
and, at the end, the inputs and CPU seconds per boundary. Every input that raised anything but the
boundary's own errors is saved under ``--found`` (for the corpus). The fuzzing runs in a worker process:
one that crashes (the C stack) is replaced, and the input it died on is kept (``crash-N.<boundary>``), with
the Python stack faulthandler wrote as it died (``crash-N.<boundary>.stack``). A
hang is bounded by ``--input-seconds`` of CPU per input (SIGPROF: on a machine shared with other work,
wall time would call slowness a hang).

``python -m tests.hardening.fuzz_campaign --minutes 60`` (the first step of ``make campaign``)."""
from __future__ import annotations

import argparse
import json
import signal
import sys
import time
import traceback
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis.errors import Unsatisfiable

from tests.hardening.boundaries import BOUNDARIES
from tests.hardening.test_fuzz_boundaries import mutated


class _Hang(Exception):
    pass


def _on_alarm(signum, frame):
    raise _Hang()


def fuzz_round(name: str, chunk: int, input_seconds: int, found: list, current: Path | None = None) -> int:
    """``chunk`` inputs to boundary ``name``; what escaped its own errors goes to ``found``. Returns the count.
    ``current``: each input is written there first, so one that crashes the interpreter is kept."""
    boundary, allowed, seeds = BOUNDARIES[name]
    count = 0

    @settings(max_examples=chunk, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(mutated(seeds))
    def one(data: bytes) -> None:
        nonlocal count
        count += 1
        if current is not None:
            current.write_bytes(data)
            current.with_suffix(".boundary").write_text(name)
        signal.setitimer(signal.ITIMER_PROF, input_seconds)  # CPU seconds: a loaded machine is no hang
        try:
            boundary(data)
        except allowed:
            pass
        except _Hang:
            found.append((name, "hang", data))
        except Exception as exc:  # noqa: BLE001 - what the campaign looks for
            found.append((name, f"{type(exc).__name__}: {str(exc)[:200]}",
                          data, traceback.format_exc(limit=4)))
        finally:
            signal.setitimer(signal.ITIMER_PROF, 0)
    try:
        one()
    except Unsatisfiable:
        pass
    return count


def worker(minutes: float, chunk: int, input_seconds: int, folder: Path) -> int:
    """Fuzz every boundary in turn for ``minutes``; a JSON line per round with the totals so far. A fatal
    signal (SIGSEGV) writes the Python stack where it struck to ``current.stack`` (faulthandler)."""
    import faulthandler

    stack_file = open(folder / "current.stack", "w")
    faulthandler.enable(file=stack_file, all_threads=False)
    signal.signal(signal.SIGPROF, _on_alarm)
    totals = {name: {"inputs": 0, "cpu_s": 0.0} for name in BOUNDARIES}
    found: list = []
    current = folder / "current.input"
    deadline = time.monotonic() + minutes * 60
    round_number = reported = 0
    while time.monotonic() < deadline:
        round_number += 1
        for name in BOUNDARIES:
            if time.monotonic() >= deadline:
                break
            cpu = time.process_time()
            totals[name]["inputs"] += fuzz_round(name, chunk, input_seconds, found, current)
            totals[name]["cpu_s"] += time.process_time() - cpu
            for item in found[reported:]:  # at once: a run that crashes later keeps what it found
                index = len(list(folder.glob("escaped-*")))
                (folder / f"escaped-{index}.{item[0]}").write_bytes(item[2])
                print(f"ESCAPED {item[0]}: {item[1]}\n{item[3] if len(item) > 3 else ''}", flush=True)
            reported = len(found)
            print(json.dumps({"round": round_number, "after": name, "escaped": len(found), "totals": totals}),
                  flush=True)
    return 1 if found else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=60.0)
    parser.add_argument("--chunk", type=int, default=50)
    parser.add_argument("--input-seconds", type=int, default=60)
    parser.add_argument("--found", default="fuzz-found", help="folder for the inputs that escaped or crashed")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    folder = Path(args.found)
    folder.mkdir(parents=True, exist_ok=True)
    if args.worker:
        from robot_bridge.processes import die_with_parent
        die_with_parent()          # a worker never fuzzes on alone after its supervisor was stopped
        return worker(args.minutes, args.chunk, args.input_seconds, folder)
    # the supervisor: a worker that dies (SIGSEGV: the C stack) is named with its input and replaced
    import subprocess

    from robot_bridge.processes import spawn
    started = time.monotonic()
    grand = {name: {"inputs": 0, "cpu_s": 0.0} for name in BOUNDARIES}
    crashes = escaped = 0
    while (left := args.minutes - (time.monotonic() - started) / 60) > 0.05:
        worker_process = spawn([sys.executable, "-m", "tests.hardening.fuzz_campaign", "--worker",
                                "--minutes", str(left), "--chunk", str(args.chunk), "--input-seconds",
                                str(args.input_seconds), "--found", str(folder)],
                               stdout=subprocess.PIPE, text=True)
        last = None
        for line in worker_process.stdout:
            print(line, end="", flush=True)
            if line.startswith('{"round"'):
                last = json.loads(line)
        code = worker_process.wait()
        if last is not None:
            for name, total in last["totals"].items():
                grand[name]["inputs"] += total["inputs"]
                grand[name]["cpu_s"] += total["cpu_s"]
            escaped += last["escaped"]
        if code < 0:
            crashes += 1
            boundary = (folder / "current.boundary").read_text() if (folder / "current.boundary").exists() else "?"
            kept = folder / f"crash-{crashes}.{boundary}"
            (folder / "current.input").replace(kept)
            stack = folder / "current.stack"
            if stack.exists():
                stack.replace(kept.with_name(kept.name + ".stack"))
            print(f"CRASH {boundary}: the worker died by signal {-code}; its input is {kept} "
                  f"(where it struck: {kept.name}.stack)", flush=True)
    print(json.dumps({"summary": {name: {"inputs": t["inputs"], "cpu_s": round(t["cpu_s"], 1)}
                                  for name, t in grand.items()}, "escaped": escaped, "crashes": crashes,
                      "minutes": args.minutes}), flush=True)
    return 1 if escaped or crashes else 0


if __name__ == "__main__":
    sys.exit(main())
