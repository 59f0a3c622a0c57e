"""Child side of the AgentSpeak benchmark: run one Jason project in this (fresh) process, report JSON.

    python -m benchmarks.asl_workload PROJECT.mas2j [--set NAME=VALUE ...] [--timeout S] [--profile N]

Runs in its own process so every workload starts from a clean heap and its peak RSS is its own.
Parse + load (``build_local_mas``) and the run (``LocalRuntime.run``) are timed separately in CPU
time, after the grammar is built once (reported apart: it is not the file's cost). The agents'
console lines are collected, not printed, so printing costs no run time.
The one JSON object on stdout is read by ``benchmarks.bench_asl``. ``--profile N`` runs the run phase
under cProfile and prints its N costliest functions (own time) to stderr: where a speed-up should look
(cProfile's own overhead inflates the CPU time reported in the JSON).
"""
from __future__ import annotations

import argparse
import json
import re
import resource
import sys
import tempfile
import time
from pathlib import Path


def rewrite_initial_belief(text: str, name: str, value: str, file: str = "<asl>") -> str:
    """Replace the single initial belief ``name(...).`` by ``name(value).`` (how a run is scaled)."""
    from agentspeak.errors import SourceError

    new, count = re.subn(rf"^{re.escape(name)}\([^)]*\)\.", f"{name}({value}).", text, flags=re.M)
    if count != 1:
        raise SourceError(f"--set {name}={value}: expected exactly one initial belief '{name}(...).' at the "
                          f"start of a line, found {count}", file=file)
    return new


def parse_sets(items: list[str]) -> dict[str, str]:
    """``["max=10"]`` -> ``{"max": "10"}``; a malformed item is a ValueError naming it."""
    sets = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name or not value:
            raise ValueError(f"--set {item!r}: expected NAME=VALUE")
        sets[name] = value
    return sets


def run_project(mas2j: str, sets: dict[str, str] | None = None, timeout: float | None = None,
                profile: int = 0) -> dict:
    """Load and run ``mas2j`` (its .asl files rewritten by ``sets``) and measure it. Returns a JSON-able dict."""
    from agentspeak.mas2j import load_mas2j

    from agents.mas_cli import build_local_mas

    from agentspeak.parser import parse_program

    t_import = time.process_time()
    parse_program("", "<grammar warm-up>")     # builds the Lark parser once per process: not the file's cost
    grammar_cpu = time.process_time() - t_import
    project = load_mas2j(mas2j)
    lines: list[str] = []
    with tempfile.TemporaryDirectory(prefix="faultmas-asl-bench-") as tmp:
        if sets:
            rewritten: dict[str, str] = {}
            for decl in project.agents:
                if decl.source not in rewritten:
                    text = Path(decl.source).read_text()
                    for name, value in sets.items():
                        text = rewrite_initial_belief(text, name, value, decl.source)
                    target = Path(tmp) / f"{len(rewritten)}-{Path(decl.source).name}"
                    target.write_text(text)
                    rewritten[decl.source] = str(target)
                decl.source = rewritten[decl.source]
        t0 = time.process_time()
        runtime = build_local_mas(project, printer=lambda name, text: lines.append(f"[{name}] {text}"))
        profiler = None
        if profile:
            import cProfile
            profiler = cProfile.Profile()
        t1 = time.process_time()
        if profiler is not None:
            why = profiler.runcall(runtime.run, timeout=timeout)
        else:
            why = runtime.run(timeout=timeout)
        t2 = time.process_time()
        if profiler is not None:
            import pstats
            pstats.Stats(profiler, stream=sys.stderr).sort_stats("tottime").print_stats(profile)
    from agentspeak._speedups import describe
    return {
        "interpreter": describe(),          # compiled or from source (agentspeak/_speedups.py)
        "lines": lines,
        "last_line": lines[-1] if lines else None,
        "grammar_cpu": grammar_cpu,
        "load_cpu": t1 - t0,
        "run_cpu": t2 - t1,
        "stopped_because": why,
        "peak_rss_kb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
        "agents": {name: {"plans": len(agent.plans.plans),
                          "rules": sum(1 for _ in agent.bb.rules())}
                   for name, agent in runtime.agents.items()},
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.asl_workload", description=__doc__.splitlines()[0])
    ap.add_argument("mas2j")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                    help="rewrite the initial belief NAME(...) of every .asl to NAME(VALUE)")
    ap.add_argument("--timeout", type=float, default=None, help="stop the run after S seconds")
    ap.add_argument("--profile", type=int, default=0, metavar="N",
                    help="profile the run phase; print its N costliest functions to stderr")
    args = ap.parse_args(argv)
    try:
        result = run_project(args.mas2j, parse_sets(args.set), args.timeout, args.profile)
    except (OSError, ValueError) as exc:          # SourceError / AslSyntaxError are ValueErrors
        print(f"{args.mas2j}: {exc}", file=sys.stderr)
        return 2
    json.dump(result, sys.stdout)
    sys.stdout.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
