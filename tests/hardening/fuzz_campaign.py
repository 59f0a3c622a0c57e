"""The long fuzz run of issue 22, by time rather than by count: every boundary of ``boundaries.BOUNDARIES`` in
turn gets ``--chunk`` mutated inputs (the strategy of ``test_fuzz_boundaries``, a fresh random seed each
round) until ``--minutes`` have passed. It prints a line per round and, at the end, the inputs and CPU
seconds per boundary and every input that raised anything but the boundary's own errors (saved under
``--found`` for the corpus). A crash of the interpreter ends the run (the last round line says where); a hang
is bounded by ``--input-seconds`` per input (SIGALRM).

``python -m tests.hardening.fuzz_campaign --minutes 60`` (``make campaign`` runs the count-based profile)."""
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


def fuzz_round(name: str, chunk: int, input_seconds: int, found: list) -> int:
    """``chunk`` inputs to boundary ``name``; what escaped its own errors goes to ``found``. Returns the count."""
    boundary, allowed, seeds = BOUNDARIES[name]
    count = 0

    @settings(max_examples=chunk, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(mutated(seeds))
    def one(data: bytes) -> None:
        nonlocal count
        count += 1
        signal.alarm(input_seconds)
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
            signal.alarm(0)
    try:
        one()
    except Unsatisfiable:
        pass
    return count


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=60.0)
    parser.add_argument("--chunk", type=int, default=50)
    parser.add_argument("--input-seconds", type=int, default=60)
    parser.add_argument("--found", default="fuzz-found", help="folder for the inputs that escaped")
    args = parser.parse_args(argv)
    signal.signal(signal.SIGALRM, _on_alarm)
    totals = {name: {"inputs": 0, "cpu_s": 0.0} for name in BOUNDARIES}
    found: list = []
    deadline = time.monotonic() + args.minutes * 60
    round_number = 0
    while time.monotonic() < deadline:
        round_number += 1
        for name in BOUNDARIES:
            if time.monotonic() >= deadline:
                break
            cpu = time.process_time()
            totals[name]["inputs"] += fuzz_round(name, args.chunk, args.input_seconds, found)
            totals[name]["cpu_s"] += time.process_time() - cpu
        print(json.dumps({"round": round_number, "inputs": sum(t["inputs"] for t in totals.values()),
                          "escaped": len(found)}), flush=True)
    folder = Path(args.found)
    for index, item in enumerate(found):
        folder.mkdir(exist_ok=True)
        (folder / f"{index}.{item[0]}").write_bytes(item[2])
        print(f"ESCAPED {item[0]}: {item[1]}\n{item[3] if len(item) > 3 else ''}", flush=True)
    print(json.dumps({"summary": {name: {"inputs": t["inputs"], "cpu_s": round(t["cpu_s"], 1)}
                                  for name, t in totals.items()}, "escaped": len(found),
                      "minutes": args.minutes}), flush=True)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
