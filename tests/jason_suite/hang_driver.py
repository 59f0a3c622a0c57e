"""Run Jason's unit suite (or some of its testers) in this process many times, each with a short overall
timeout, and stop at the first run that does not end: then print what the agents wait for (issue 21).

    python -m tests.jason_suite.hang_driver [--only REGEX] [--runs N] [--timeout S] [--watch a,b]
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

from tests.jason_suite.__main__ import DEFAULT_DIR

MAS = """MAS hang_driver {{
    agents:
        test_manager [ goals="create_tester_agents(\\"./src/test/jason\\",\\"{only}\\",\\"/inc\\")",
                       beliefs="shutdown_delay(600)" ];
    aslSourcePath: "{inc}"; "{asl}";
}}
"""


def dump(runtime, names: list[str]) -> None:
    """What each named agent holds: beliefs, events, intentions and what they wait for, timers, asks."""
    from agentspeak.terms import to_str
    for name in names:
        agent = runtime.agents.get(name)
        if agent is None:
            print(f"== {name}: not in the MAS")
            continue
        print(f"== {name}: cycles={agent.cycles} sleeping_evt={agent.sleeping_evt} mailbox={list(agent.mailbox)} "
              f"events={list(agent.events)} feedback={len(agent.feedback)} pending_futures={agent.pending_futures}")
        print("   beliefs:", [to_str(b) for b in agent.bb.literals() if getattr(b, 'functor', '') in
                              ('sleeping', 'retrieve_info', 'mock_owner')])
        print("   timers (due in s):", [round(w + agent.timer_lag - agent.clock(), 3) for w, _, _ in agent.timers],
              "lag", round(agent.timer_lag, 3))
        print("   pending_asks:", agent.pending_asks)
        print("   condition_waiters:", [(i.id, s.reason) for i, s in agent.condition_waiters])
        print("   event_waiters:", [(str(t), i.id, s.reason) for t, i, s in agent.event_waiters])
        for intention in agent.intentions():
            w = intention.waiting
            print(f"   intention {intention.id} waiting={getattr(w, 'reason', w)} "
                  f"term={getattr(w, 'term', None)} suspended={intention.suspended}")
            for im in intention.stack:
                print(f"      {im!r}")


def one_run(suite: Path, mas_file: Path, timeout: float, watch: list[str]) -> bool:
    """True if the run ended by itself."""
    from agentspeak.mas2j import load_mas2j
    from agents.mas_cli import build_local_mas
    cwd = os.getcwd()
    os.chdir(suite)
    try:
        runtime = build_local_mas(load_mas2j(str(mas_file)))
        why = runtime.run(timeout=timeout)
        if why == "timeout":
            print(f"HANG (run cut after {timeout} s); agents: {sorted(runtime.agents)}")
            dump(runtime, watch)
            return False
        return True
    finally:
        os.chdir(cwd)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.jason_suite.hang_driver")
    parser.add_argument("suite_dir", nargs="?", default=str(DEFAULT_DIR))
    parser.add_argument("--only", default=".*.asl", help="regex of the tester files (Jason's .list_files)")
    parser.add_argument("--runs", type=int, default=50)
    parser.add_argument("--timeout", type=float, default=30.0)
    parser.add_argument("--watch", default="send,tom,test_manager")
    args = parser.parse_args(argv)
    import logging
    logging.basicConfig(level=logging.ERROR)
    suite = Path(args.suite_dir).resolve()
    jason = suite / "src/test/jason"
    with tempfile.TemporaryDirectory() as tmp:
        mas_file = Path(tmp) / "hang_driver.mas2j"
        mas_file.write_text(MAS.format(only=args.only, inc=jason / "inc", asl=jason / "asl"))
        for run in range(1, args.runs + 1):
            started = time.monotonic()
            ok = one_run(suite, mas_file, args.timeout, args.watch.split(","))
            print(f"run {run}: {'ok' if ok else 'HANG'} in {time.monotonic() - started:.1f} s", flush=True)
            if not ok:
                return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
