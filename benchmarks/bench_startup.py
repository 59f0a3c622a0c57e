"""Whole-process start-up (issue 23): what a user waits for, from typing the command to the prompt.

Every row is a fresh process started the way a user starts it (the ``faultmas`` script of this venv),
timed from outside: wall seconds and CPU seconds (user + system of the child, from ``os.wait4``), each the
median of the runs; on a busy shared machine the CPU column is the steadier one, so the ratios are given
for both. All sides run in this one benchmark, interleaved, so the ratios compare like with like:

* ``python -c pass`` (the floor: this venv's interpreter), ``faultmas --help``
  and ``faultmas asl run hello.asl`` against the issue's targets (0.08 s and 0.10 s);
* every program of the shared AgentSpeak benchmarks as ``faultmas mas run X.mas2j`` against
  python-agentspeak's ``pyagentspeak_run.py X.asl`` (same sizes; quick mode scales them down);
* diagnosis: ``faultmas diagnose C.bench --obs O.json --max-card 3`` against ``benchmarks/pysat_script.py``,
  a plain python-sat script (stdlib + python-sat: its own encoding, pysat's Hitman over conflicts), on one
  instance per ISCAS-85 circuit size, each checked to give the same diagnoses. faultmas runs with the netlist
  kept by its first run (``diagnosis/netlist_cache.py``, as a user's second run of a file), that first run in a
  column of its own; ``FAULTMAS_BENCH_INSTRUCTIONS=1`` adds instruction counts (valgrind; minutes). A floor
  row (``benchmarks/startup_floor.py``: interpreter, argparse, json, python-sat's solver extension, which every
  python-sat command-line tool runs before its first file) gives per circuit the best ratio reachable at all
  (script / floor), so a target above it shows as out of reach ("NO: floor"), not as work left undone.

The grammar tables are built once before timing (a user's first run builds them; see
``agentspeak/lark_loader.py``); that first run is reported on its own line. The programs run again are loaded
from the parse cache (``agentspeak/parse_cache.py``, as a user's second run of a file); a file not run before
(parsed, with the tables kept) has its own line too. The children run without
``PYTHONDONTWRITEBYTECODE`` (a user's Python writes ``.pyc`` files, and pip writes them at install): with it
set, as in some sandboxes, every faultmas module would be compiled from source on every start.

Every child starts as from a user's shell: without the ROS 2 wheels' ``_ROS_WHEELS_BOOTSTRAP_COMPLETE`` and
``LD_LIBRARY_PATH``, which this process may have and children would inherit (then no child would pay what a
user's start pays). So the faultmas rows, ``python -c pass`` and the python-sat script (all this venv's
interpreter) start alike: once, as ``_faultmas_ros_libraries.pth`` keeps the ROS wheels' bootstrapper from
re-executing a process that never imports ROS; with ``FAULTMAS_ROS_REEXEC=1`` in the environment every one
of them pays the re-exec again (the way before it). python-agentspeak runs in its own venv, which has no ROS
wheels and never re-executed.
"""
from __future__ import annotations

import json
import os
import shutil
import statistics
import sys
import tempfile
import time
import zlib
from pathlib import Path

from benchmarks.bench_asl import (ASL_DIR, WORKLOADS, ChildRun, Workload, _pyas_line, _tail, baseline_python,
                                  clean_env_for_other_venv, run_child)

REPO = Path(__file__).resolve().parent.parent
ISCAS = REPO.parent / "shared" / "benchmarks" / "iscas85"
FAULTMAS = Path(sys.executable).with_name("faultmas")
HELLO = '!start.\n+!start <- .print("hello world").\n'
TARGET_HELP, TARGET_HELLO, TARGET_RATIO = 0.08, 0.10, 3.0
ASL_ROWS = ("count", "ring10", "ring100", "beliefs-fill", "beliefs", "fib", "reverse", "parse2000")
CIRCUITS = ("c17", "c432", "c499", "c880", "c1355", "c1908")   # small to medium: where start-up counts


class Timing:
    """Wall seconds and CPU seconds of several runs of one command."""

    def __init__(self) -> None:
        self.wall: list[float] = []
        self.cpu: list[float] = []
        self.error = ""

    def add(self, wall: float, child: ChildRun) -> ChildRun:
        self.wall.append(wall)
        self.cpu.append(child.cpu)
        return child

    def cell(self) -> str:
        if self.error:
            return "FAILED"
        return f"{statistics.median(self.wall):.3f} / {statistics.median(self.cpu):.3f}"

    @property
    def wall_median(self) -> float:
        return statistics.median(self.wall)

    @property
    def cpu_median(self) -> float:
        return statistics.median(self.cpu)


def user_env() -> dict[str, str]:
    """This environment as a user's shell has it: bytecode caches written, no ROS bootstrap variables (see the
    module doc)."""
    return {k: v for k, v in os.environ.items()
            if k not in ("PYTHONDONTWRITEBYTECODE", "_ROS_WHEELS_BOOTSTRAP_COMPLETE", "LD_LIBRARY_PATH")}


def reexec_state() -> str:
    """Whether this venv's interpreter re-executes itself at start (the ROS wheels' bootstrapper), as a child
    started from a user's shell finds out."""
    child = run_child([sys.executable, "-c", "import os; print(os.environ.get('_ROS_WHEELS_BOOTSTRAP_COMPLETE'))"],
                      env=user_env())
    return "re-executed at start (ROS wheels)" if child.stdout.strip() == "1" else "started once"


def _ratio_cells(ours: Timing, theirs: Timing) -> tuple[float | None, str]:
    """(wall ratio, ``"wall x / CPU x"``): how many times faster faultmas is, None when a side failed."""
    if ours.error or theirs.error or not ours.wall or not theirs.wall:
        return None, "-"
    wall = theirs.wall_median / ours.wall_median
    return wall, f"{wall:.1f}x / {theirs.cpu_median / ours.cpu_median:.1f}x"


def _timed(timing: Timing, cmd: list[str], env: dict[str, str] | None = None) -> ChildRun:
    started = time.perf_counter()
    child = run_child(cmd, env=user_env() if env is None else env)
    return timing.add(time.perf_counter() - started, child)


def _check(timing: Timing, child: ChildRun, expected: str | None = None) -> None:
    if child.returncode != 0:
        timing.error = f"exit {child.returncode}: {_tail(child.stderr)}"
    elif expected is not None and expected not in child.stdout:
        timing.error = f"expected {expected!r}, got {_tail(child.stdout)!r}"


def _startup_rows(tmp: Path, repeats: int) -> list[str]:
    hello = tmp / "hello.asl"
    hello.write_text(HELLO)
    commands = {"python -c pass": ([sys.executable, "-c", "pass"], None, None),
                "faultmas --help": ([str(FAULTMAS), "--help"], TARGET_HELP, "COMMAND"),
                "faultmas asl run hello.asl": ([str(FAULTMAS), "asl", "run", str(hello)], TARGET_HELLO,
                                               "[hello] hello world")}
    first = Timing()
    cache = tmp / "user-cache"              # a user's very first run: grammar tables built, nothing parsed before
    env = {**user_env(), "FAULTMAS_CACHE_DIR": str(cache)}
    _check(first, _timed(first, commands["faultmas asl run hello.asl"][0], env=env), "hello world")
    timings = {name: Timing() for name in commands}
    edited = Timing()                       # a file not run before (grammar tables kept; the file is parsed)
    for run in range(repeats):              # interleaved: a burst of load hits every row alike
        for name, (cmd, _, expected) in commands.items():
            _check(timings[name], _timed(timings[name], cmd, env=env), expected)
        new = tmp / f"edited{run}.asl"
        new.write_text(f"// edit {run}\n{HELLO}")
        _check(edited, _timed(edited, [str(FAULTMAS), "asl", "run", str(new), "--name", "hello"], env=env),
               "[hello] hello world")
    rows = [f"{'command':32} {'wall / CPU, medians (s)':>26}  target  met?"]
    for name, (_, target, _) in commands.items():
        t = timings[name]
        met = "-" if target is None else "FAILED" if t.error else "yes" if t.wall_median <= target else "NO"
        rows.append(f"{name:32} {t.cell():>26}  {'-' if target is None else f'<={target:.2f}':>6}  {met}"
                    + (f"  ({t.error})" if t.error else ""))
    rows.append(f"{'  a file not run before':32} {edited.cell():>26}  (parsed: agentspeak/parse_cache.py)")
    rows.append(f"{'  first run ever (builds tables)':32} {first.cell():>26}")
    return rows


def _asl_project(tmp: Path, workload: Workload, quick: bool) -> Path:
    """The workload's .mas2j and .asl copied to ``tmp``, its size beliefs rewritten (quick mode)."""
    from benchmarks.asl_workload import rewrite_initial_belief

    where = tmp / workload.name
    where.mkdir(exist_ok=True)
    shutil.copy(ASL_DIR / workload.mas2j, where / workload.mas2j)
    text = (ASL_DIR / workload.asl).read_text()
    for name, value in workload.sets(quick).items():
        text = rewrite_initial_belief(text, name, str(value), workload.asl)
    (where / workload.asl).write_text(text)
    return where


def _asl_rows(tmp: Path, quick: bool, repeats: int) -> list[str]:
    python, why = baseline_python()
    rows = [f"{'program (whole process)':24} {'faultmas wall / CPU':>20} {'python-agentspeak':>20} "
            f"{'ratio wall / CPU':>16}  target  met?"]
    for name in ASL_ROWS:
        workload = WORKLOADS[name]
        where = _asl_project(tmp, workload, quick)
        expected = workload.expected(workload.sizes(quick))
        ours, theirs = Timing(), Timing()
        run_child([str(FAULTMAS), "mas", "run", str(where / workload.mas2j)], env=user_env())   # parsed once, kept
        for _ in range(repeats):
            _check(ours, _timed(ours, [str(FAULTMAS), "mas", "run", str(where / workload.mas2j)]), expected)
            if python is not None and not (name == "beliefs" and theirs.wall):   # its join: ~20 s, once
                cmd = [str(python), str(ASL_DIR / "pyagentspeak_run.py"), str(where / workload.asl),
                       *(["--ring", str(workload.ring)] if workload.ring else [])]
                child = _timed(theirs, cmd, env={k: v for k, v in clean_env_for_other_venv().items()
                                                 if k != "PYTHONDONTWRITEBYTECODE"})
                _check(theirs, child)
                if not theirs.error and _pyas_line(_tail(child.stdout)) != _pyas_line(expected):
                    theirs.error = f"last line {_tail(child.stdout)!r}"
        ratio, ratios = _ratio_cells(ours, theirs)
        met = "FAILED" if ratio is None else "yes" if ratio >= TARGET_RATIO else "NO"
        rows.append(f"{name:24} {ours.cell():>20} {theirs.cell() if python else 'unavailable':>20} "
                    f"{ratios:>16}  >={TARGET_RATIO:.0f}x  {met}"
                    + "".join(f"  ({side}: {t.error})" for side, t in (("faultmas", ours), ("baseline", theirs))
                              if t.error))
    if python is None:
        rows.append(f"python-agentspeak unavailable: {why}")
    return rows


def instruction_count(cmd: list[str], env: dict[str, str]) -> float | None:
    """Millions of instructions the process runs (valgrind's callgrind, following a re-exec): the same on a busy
    machine as on a quiet one. None when valgrind is missing or the command failed."""
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        return None
    child = run_child([valgrind, "--tool=callgrind", "--trace-children=yes", "--callgrind-out-file=/dev/null", *cmd],
                      env=env, timeout=1800)
    counts = [int(line.split()[-1].replace(",", "")) for line in child.stderr.splitlines() if "Collected :" in line]
    return sum(counts) / 1e6 if child.returncode == 0 and counts else None


def _diagnosis_rows(tmp: Path, repeats: int) -> list[str]:
    """The diagnosis rows; ``faultmas`` runs with the netlist kept from its first run (``diagnosis/netlist_cache.py``,
    as a user's second run of a file), that first run on a line of its own. With ``FAULTMAS_BENCH_INSTRUCTIONS=1``
    every instance is also counted in instructions (valgrind, minutes), which load does not change.

    The floor (``benchmarks/startup_floor.py``: the interpreter, argparse parsing the same command line, json and
    python-sat's solver extension, what every python-sat command-line tool runs before its first file) runs
    interleaved with both sides, with the same arguments; per circuit, "reachable" is the script over the floor
    (in seconds: the floor's runs beside that circuit's, under the same load; its row: all of them):
    the best ratio any such tool can reach there, and a target above it is out of reach at this interpreter."""
    from diagnosis.bench import parse_bench
    from benchmarks.bench_diagnosis import make_instances

    count = os.environ.get("FAULTMAS_BENCH_INSTRUCTIONS", "") not in ("", "0")
    rows = [f"{'circuit (whole process)':24} {'faultmas wall / CPU':>20} {'python-sat script':>20} "
            f"{'ratio wall / CPU':>16} {'reachable':>11}  target  {'met?':10} {'first run ever':>15}"
            + (f"  {'instructions (M) faultmas / script / ratio / reachable':>56}" if count else "")]
    script = Path(__file__).with_name("pysat_script.py")
    floor_script = Path(__file__).with_name("startup_floor.py")
    env = {**user_env(), "FAULTMAS_CACHE_DIR": str(tmp / "user-cache")}
    floor = Timing()
    floor_count: float | None = None
    circuits = []
    for name in CIRCUITS:
        bench = ISCAS / f"{name}.bench"
        netlist = parse_bench(bench)
        (_, observations), = make_instances(netlist, 1, [2], seed=zlib.crc32(name.encode()))
        obs = tmp / f"{name}.json"
        obs.write_text(json.dumps({k: int(v) for k, v in observations.items()}))
        ours, theirs, first, floor_here = Timing(), Timing(), Timing(), Timing()
        ours_answer = theirs_answer = None
        arguments = [str(bench), "--obs", str(obs), "--max-card", "3", "--json"]
        diagnose = [str(FAULTMAS), "diagnose", *arguments]
        baseline = [sys.executable, str(script), str(bench), str(obs), "3"]
        floor_cmd = [sys.executable, str(floor_script), "diagnose", *arguments]
        _check(first, _timed(first, diagnose, env=env))        # reads and encodes the netlist, keeps it
        for _ in range(repeats):
            child = _timed(ours, diagnose, env=env)
            _check(ours, child)
            if not ours.error:
                ours_answer = sorted(sorted(d) for d in json.loads(child.stdout)["diagnoses"])
            child = _timed(theirs, baseline)
            _check(theirs, child)
            if not theirs.error:
                theirs_answer = sorted(sorted(d) for d in json.loads(child.stdout))
            _check(floor_here, _timed(floor_here, floor_cmd))   # beside this circuit's runs: the same load
        floor.wall += floor_here.wall
        floor.cpu += floor_here.cpu
        floor.error = floor.error or floor_here.error
        if not (ours.error or theirs.error) and ours_answer != theirs_answer:
            ours.error = f"{len(ours_answer)} diagnoses, the script found {len(theirs_answer)} (not the same)"
        counts = None
        if count:
            if floor_count is None:
                floor_count = instruction_count(floor_cmd, user_env())
            counts = (instruction_count(diagnose, env), instruction_count(baseline, user_env()))
        circuits.append((f"{name} ({len(netlist.gates)} gates)", ours, theirs, first, floor_here, counts))
    for label, ours, theirs, first, floor_here, counts in circuits:
        ratio, ratios = _ratio_cells(ours, theirs)
        best, bests = _ratio_cells(floor_here, theirs)
        instructions, best_count = "", None
        if counts is not None:
            mine, script_count = counts
            if mine and script_count and floor_count:
                best_count = script_count / floor_count
                instructions = (f"  {mine:>20.0f} / {script_count:>6.0f} / {script_count / mine:>5.2f}x"
                                f" / {best_count:>5.2f}x")
            else:
                instructions = "  (valgrind failed)"
        met = ("FAILED" if ratio is None else "yes" if ratio >= TARGET_RATIO     # wall, as the other tables
               else "NO: floor" if best is not None and best < TARGET_RATIO else "NO")
        rows.append(f"{label:24} {ours.cell():>20} {theirs.cell():>20} {ratios:>16} {bests:>11}"
                    f"  >={TARGET_RATIO:.0f}x  {met:10} {first.cell():>15}{instructions}"
                    + "".join(f"  ({side}: {t.error})" for side, t in (("faultmas", ours), ("script", theirs),
                                                                       ("first run", first)) if t.error))
    rows.append((f"{'floor (startup_floor.py)':24} {floor.cell():>20} {'':>20} {'':>16} {'':>11}  {'':6}  {'':10} "
                 f"{'':>15}" + (f"  {floor_count:>20.0f}" if count and floor_count else "")).rstrip()
                + (f"  ({floor.error})" if floor.error else ""))
    rows.append("reachable: the script over the floor (interpreter + argparse + json + python-sat's solver extension,"
                " benchmarks/startup_floor.py), the best ratio a tool whose own work cost nothing would reach;"
                " 'NO: floor': the target is above it (wall)")
    return rows


def run(quick: bool = False) -> str:
    repeats = 3 if quick else 7
    with tempfile.TemporaryDirectory(prefix="faultmas-bench-startup-") as name:
        tmp = Path(name)
        lines = [f"whole process, {repeats} runs each, interleaved; seconds: wall / CPU (user + system), medians; "
                 f"load average at start {os.getloadavg()[0]:.1f}; this venv's interpreter: {reexec_state()}"]
        lines += _startup_rows(tmp, repeats)
        lines.append("")
        if (ASL_DIR / "README.md").exists():
            lines.append("AgentSpeak programs" + (" (quick: scaled-down sizes)" if quick else " (their default sizes)"))
            lines += _asl_rows(tmp, quick, 1 if quick else 3)
        else:
            lines.append(f"AgentSpeak programs skipped: {ASL_DIR} not found")
        lines.append("")
        if ISCAS.is_dir():
            lines.append("diagnosis: all minimal diagnoses up to size 3, one instance (2 flipped gates) per circuit")
            lines += _diagnosis_rows(tmp, repeats)
        else:
            lines.append(f"diagnosis skipped: {ISCAS} not found")
    return "\n".join(lines)


if __name__ == "__main__":
    print(run(quick="--quick" in sys.argv))
