"""AgentSpeak benchmark (issue 2): faultmas against python-agentspeak 0.2.2 on the shared Jason workloads.

The programs live in ``../shared/benchmarks/asl/`` (override with FAULTMAS_ASL_BENCH_DIR); their README
defines the units of work and the exact expected output lines. Every run is a fresh process:

* faultmas: ``python -m benchmarks.asl_workload`` in this interpreter (the project venv). It times
  parse + load and the run separately in CPU time; the row uses the run phase (the load phase for
  parse2000) and a wrong or missing last output line makes the row FAILED instead of a number.
* python-agentspeak: the shared ``pyagentspeak_run.py`` in its own venv ``.venv-pyas/`` (created once).
  PyPI ``agentspeak`` installs a top-level ``agentspeak`` module like faultmas does, so the two can never
  share one environment (nor can faultmas and SPADE-BDI, which depends on it). Its CPU time is the
  child's (``os.wait4``) minus the least CPU of a start-up run (``count.asl`` with ``max(0)``).

Beliefs join rate = queries / (CPU(queries=N) - CPU(queries=0)), as the shared README measures it.
Rows take the least CPU time of 5 runs (1 in quick mode, which also scales the size beliefs down): on a
shared machine other processes only ever add time, so the minimum is steadier than the median.
python-agentspeak's full-size join (~16 s CPU) runs once.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

REPO = Path(__file__).resolve().parent.parent
ASL_DIR = Path(os.environ.get("FAULTMAS_ASL_BENCH_DIR", REPO.parent / "shared" / "benchmarks" / "asl"))
BASELINE_VENV = REPO / ".venv-pyas"
BASELINE_SPEC = ("agentspeak", "0.2.2")
CHILD_TIMEOUT = 300.0
REPEATS = 5


def _fib(n: int) -> int:
    a, b = 0, 1
    for _ in range(n):
        a, b = b, a + b
    return a


@dataclass(frozen=True)
class Workload:
    """One program run: which files, its size beliefs, the line it must print and its units of work."""

    name: str
    mas2j: str
    asl: str
    defaults: dict[str, int]                  # the size beliefs as written in the .asl file
    expected: Callable[[dict[str, int]], str]
    work: Callable[[dict[str, int]], int]
    fixed: dict[str, int] = field(default_factory=dict)   # always rewritten (e.g. queries=0)
    quick: dict[str, int] = field(default_factory=dict)   # rewritten in quick mode only
    ring: int = 0
    phase: str = "run"                        # "load" (parse + load) for parse2000

    def sets(self, quick: bool) -> dict[str, int]:
        return {**(self.quick if quick else {}), **self.fixed}      # fixed wins: the fill run keeps queries=0

    def sizes(self, quick: bool) -> dict[str, int]:
        return {**self.defaults, **self.sets(quick)}


def _ring(k: int) -> Workload:
    return Workload(f"ring{k}", f"ring{k}.mas2j", "ring.asl", {"max_hops": 10_000},
                    lambda s: f"[ring0] ring done {s['max_hops']}", lambda s: s["max_hops"],
                    quick={"max_hops": 2_000}, ring=k)


def _beliefs(name: str, fixed: dict[str, int]) -> Workload:
    return Workload(name, "beliefs.mas2j", "beliefs.asl", {"size": 100, "queries": 1000},
                    lambda s: f"[beliefs] beliefs done {s['size'] ** 2} {s['queries']}",
                    lambda s: s["size"] ** 2, fixed=fixed, quick={"size": 30, "queries": 500})


WORKLOADS: dict[str, Workload] = {w.name: w for w in [
    Workload("count", "count.mas2j", "count.asl", {"max": 100_000},
             lambda s: f"[count] count done {s['max']}", lambda s: s["max"], quick={"max": 10_000}),
    _ring(10),
    _ring(100),
    _beliefs("beliefs-fill", {"queries": 0}),
    _beliefs("beliefs", {}),
    Workload("fib", "fib.mas2j", "fib.asl", {"n": 20},
             lambda s: f"[fib] fib {s['n']} {_fib(s['n'])}", lambda s: 2 * _fib(s["n"] + 1) - 1, quick={"n": 15}),
    Workload("reverse", "reverse.mas2j", "reverse.asl", {"n": 1000},
             lambda s: f"[reverse] reverse {s['n']} 0 {s['n'] - 1}", lambda s: 2 * (s["n"] + 1),
             quick={"n": 200}),
    Workload("parse2000", "parse.mas2j", "parse2000.asl", {}, lambda s: "[parse] parse ok", lambda s: 2001,
             phase="load"),
]}
PARSE_PLANS, PARSE_RULES = 2001, 10


@dataclass
class Result:
    """One side's measurement of one workload: CPU seconds per run (empty if it failed)."""

    seconds: list[float] = field(default_factory=list)
    peak_rss_kb: int = 0
    error: str = ""
    detail: dict = field(default_factory=dict)

    @property
    def best(self) -> float | None:
        """The least CPU time of the runs (what the table reports), None if a run failed."""
        return min(self.seconds) if self.seconds and not self.error else None


# ---------------------------------------------------------------------------------------------- children
def clean_env_for_other_venv() -> dict[str, str]:
    """This venv's ROS bootstrap variables would make another venv's interpreter load our ROS libraries."""
    env = dict(os.environ)
    for key in ("_ROS_WHEELS_BOOTSTRAP_COMPLETE", "LD_LIBRARY_PATH"):
        env.pop(key, None)
    return env


@dataclass
class ChildRun:
    returncode: int
    stdout: str
    stderr: str
    cpu: float            # user + system CPU of the child
    maxrss_kb: int


def run_child(cmd: list[str], env: dict[str, str] | None = None, timeout: float = CHILD_TIMEOUT) -> ChildRun:
    """Run ``cmd`` and reap it with ``os.wait4`` so its own CPU time and peak RSS are known exactly."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        proc = subprocess.Popen(cmd, stdout=out, stderr=err, stdin=subprocess.DEVNULL, env=env, cwd=REPO)
        timer = threading.Timer(timeout, proc.kill)
        timer.start()
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        except BaseException:             # e.g. Ctrl-C: do not leave the child running
            proc.kill()
            proc.wait()
            raise
        finally:
            timer.cancel()
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        return ChildRun(proc.returncode, out.read().decode(errors="replace"), err.read().decode(errors="replace"),
                        usage.ru_utime + usage.ru_stime, usage.ru_maxrss)


def _set_args(sets: dict[str, int]) -> list[str]:
    return [f"--set={name}={value}" for name, value in sets.items()]


def _tail(text: str) -> str:
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return lines[-1][:160] if lines else "(no output)"


# ---------------------------------------------------------------------------------------------- faultmas
def run_faultmas(workload: Workload, quick: bool, repeats: int = 1, from_source: bool = False) -> Result:
    """Run ``workload`` on faultmas ``repeats`` times, each in a fresh process, checking its last line.
    ``from_source``: with the compiled interpreter switched off (FAULTMAS_PURE_PYTHON=1)."""
    from agentspeak._speedups import PURE_ENV
    env = {k: v for k, v in os.environ.items() if k != PURE_ENV}
    if from_source:
        env[PURE_ENV] = "1"
    sizes = workload.sizes(quick)
    expected = workload.expected(sizes)
    cmd = [sys.executable, "-m", "benchmarks.asl_workload", str(ASL_DIR / workload.mas2j),
           *_set_args(workload.sets(quick)), "--timeout", str(CHILD_TIMEOUT)]
    result = Result()
    for _ in range(repeats):
        child = run_child(cmd, env=env, timeout=CHILD_TIMEOUT + 30)
        if child.returncode != 0:
            result.error = f"exit {child.returncode}: {_tail(child.stderr)}"
            return result
        try:
            data = json.loads(child.stdout)
        except json.JSONDecodeError:
            result.error = f"no JSON report on stdout: {_tail(child.stdout)!r}"
            return result
        result.detail = data
        if data["last_line"] != expected:
            result.error = f"last line {data['last_line']!r}, expected {expected!r}"
            return result
        if data["stopped_because"] != "idle":
            result.error = f"run ended by {data['stopped_because']}, not by going idle"
            return result
        if workload.phase == "load":
            held = next(iter(data["agents"].values()))
            if (held["plans"], held["rules"]) != (PARSE_PLANS, PARSE_RULES):
                result.error = (f"loaded {held['plans']} plans and {held['rules']} rules, "
                                f"expected {PARSE_PLANS} and {PARSE_RULES}")
                return result
        result.seconds.append(data["load_cpu"] if workload.phase == "load" else data["run_cpu"])
        result.peak_rss_kb = max(result.peak_rss_kb, data["peak_rss_kb"])
    return result


# ---------------------------------------------------------------------------------------------- baseline
_baseline_cache: dict[str, object] = {}


def _baseline_version(python: Path) -> str | None:
    if not python.exists():
        return None
    probe = run_child([str(python), "-c", "import importlib.metadata as m; print(m.version('agentspeak'))"],
                      env=clean_env_for_other_venv(), timeout=60)
    return probe.stdout.strip() if probe.returncode == 0 else None


def baseline_python() -> tuple[Path | None, str]:
    """The interpreter of ``.venv-pyas`` with python-agentspeak 0.2.2, created once; else (None, why not)."""
    if "python" in _baseline_cache:
        return _baseline_cache["python"], _baseline_cache["why"]  # type: ignore[return-value]
    python = BASELINE_VENV / "bin" / "python"
    name, version = BASELINE_SPEC
    why = ""
    if _baseline_version(python) != version:
        env = clean_env_for_other_venv()
        steps = [[sys.executable, "-m", "venv", "--clear", str(BASELINE_VENV)],
                 [str(python), "-m", "pip", "install", "-q", "--disable-pip-version-check", f"{name}=={version}"]]
        for step in steps:
            try:
                done = run_child(step, env=env, timeout=600)
            except OSError as exc:
                why = f"{step[0]}: {exc}"
                break
            if done.returncode != 0:
                why = f"'{' '.join(step[2:5])}' failed: {_tail(done.stderr)}"
                break
        if not why and _baseline_version(python) != version:
            why = f"{name}=={version} not importable in {BASELINE_VENV}"
    _baseline_cache.update(python=None if why else python, why=why)
    return _baseline_cache["python"], why  # type: ignore[return-value]


def _pyas_line(line: str) -> str:
    """python-agentspeak prints ``<agent> a  b``; Jason prints ``[agent] ab``: compare without name and spaces."""
    return " ".join(line.split()[1:])


def run_baseline(python: Path, workload: Workload, quick: bool, repeats: int, startup: float) -> Result:
    """Run ``workload`` on python-agentspeak; CPU = the child's CPU minus the start-up run's."""
    sizes = workload.sizes(quick)
    expected = _pyas_line(workload.expected(sizes))
    cmd = [str(python), str(ASL_DIR / "pyagentspeak_run.py"), str(ASL_DIR / workload.asl),
           *(["--ring", str(workload.ring)] if workload.ring else []), *_set_args(workload.sets(quick))]
    result = Result()
    for _ in range(repeats):
        child = run_child(cmd, env=clean_env_for_other_venv())
        if child.returncode != 0:
            result.error = f"exit {child.returncode}: {_tail(child.stderr)}"
            return result
        got = _pyas_line(_tail(child.stdout))
        if got != expected:
            result.error = f"last line {got!r}, expected {expected!r}"
            return result
        result.seconds.append(max(child.cpu - startup, 1e-9))
        result.peak_rss_kb = max(result.peak_rss_kb, child.maxrss_kb)
        result.detail = {"stderr": child.stderr.strip()}
    return result


def baseline_startup(python: Path, repeats: int) -> float:
    """CPU of starting python-agentspeak on a program that does nothing (count to 0)."""
    count = WORKLOADS["count"]
    cmd = [str(python), str(ASL_DIR / "pyagentspeak_run.py"), str(ASL_DIR / count.asl), "--set=max=0"]
    run_child(cmd, env=clean_env_for_other_venv())      # warm-up: a fresh venv compiles its .pyc files first
    return min(run_child(cmd, env=clean_env_for_other_venv()).cpu for _ in range(repeats))


# ---------------------------------------------------------------------------------------------- table
@dataclass(frozen=True)
class Row:
    label: str
    workload: str         # whose faultmas peak RSS the row shows
    unit: str
    target: str
    rate: Callable[[dict[str, Result], bool], tuple[float | None, float | None, str]]   # (rate, seconds, error)
    met: Callable[[float, dict[str, Result], bool], bool] | None = None   # (rate, results, quick)


def _plain(name: str) -> Callable[[dict[str, Result], bool], tuple[float | None, float | None, str]]:
    def rate(results: dict[str, Result], quick: bool):
        r = results[name]
        if r.best is None:
            return None, None, r.error
        return WORKLOADS[name].work(WORKLOADS[name].sizes(quick)) / r.best, r.best, ""
    return rate


def _join(results: dict[str, Result], quick: bool):
    full, fill = results["beliefs"], results["beliefs-fill"]
    if full.best is None or fill.best is None:
        return None, None, full.error or fill.error
    seconds = full.best - fill.best
    if seconds <= 0:
        return None, None, f"join time {seconds:.3f} s <= 0 (noise larger than the queries)"
    return WORKLOADS["beliefs"].sizes(quick)["queries"] / seconds, seconds, ""


ROWS = [
    Row("count", "count", "goals/s", ">=150k, <100 MB", _plain("count"),
        lambda rate, res, quick: rate >= 150_000 and res["count"].peak_rss_kb < 100 * 1024),
    Row("ring, 10 agents", "ring10", "hops/s", ">=100k", _plain("ring10"), lambda rate, res, quick: rate >= 100_000),
    Row("ring, 100 agents", "ring100", "hops/s", ">=100k, >=0.9x ring10", _plain("ring100"),
        lambda rate, res, quick: rate >= 100_000 and rate >= 0.9 * (_plain("ring10")(res, quick)[0] or 0)),
    Row("beliefs fill", "beliefs-fill", "beliefs/s", "-", _plain("beliefs-fill")),
    Row("beliefs join", "beliefs", "queries/s", ">=5,000", _join, lambda rate, res, quick: rate >= 5_000),
    Row("fib (rules)", "fib", "calls/s", ">=50k", _plain("fib"), lambda rate, res, quick: rate >= 50_000),
    Row("reverse (rules)", "reverse", "calls/s", "-", _plain("reverse")),
    Row("parse2000 load", "parse2000", "plans/s", "load <=1 s", _plain("parse2000"),
        lambda rate, res, quick: res["parse2000"].best <= 1.0),
]


def _fmt_rate(rate: float | None, seconds: float | None, error: str) -> str:
    if error:
        return "FAILED"
    return f"{rate:,.0f} ({seconds:.3f} s)"


def render(results: dict[str, Result], baseline: dict[str, Result] | None, baseline_why: str, quick: bool,
           source: dict[str, Result] | None = None) -> str:
    """The side-by-side table (faultmas, faultmas run from source if ``source``, python-agentspeak, ratio,
    target) with failures listed below it. Targets are judged on the first column: the default install."""
    header = ["benchmark", "unit", "faultmas (CPU)", *(["from source (CPU)"] if source else []),
              "python-agentspeak (CPU)", "ratio", "target", "met?", "faultmas peak RSS"]
    rows, notes = [], []
    for row in ROWS:
        rate, seconds, error = row.rate(results, quick)
        if error:
            notes.append(f"{row.label}, faultmas: {error}")
        source_cells = []
        if source:
            s_rate, s_seconds, s_error = row.rate(source, quick)
            source_cells = [_fmt_rate(s_rate, s_seconds, s_error)]
            if s_error:
                notes.append(f"{row.label}, faultmas from source: {s_error}")
        if baseline is None:
            b_rate, b_seconds, b_error = None, None, ""
            b_text = "baseline unavailable"
        else:
            b_rate, b_seconds, b_error = row.rate(baseline, quick)
            b_text = _fmt_rate(b_rate, b_seconds, b_error)
            if b_error:
                notes.append(f"{row.label}, python-agentspeak: {b_error}")
        ratio = f"{rate / b_rate:.1f}x" if rate and b_rate else "-"
        if rate is None:
            met = "FAILED"
        elif row.met is None:
            met = "-"
        else:
            met = "yes" if row.met(rate, results, quick) else "NO"
        rss = results[row.workload].peak_rss_kb
        rows.append([row.label, row.unit, _fmt_rate(rate, seconds, error), *source_cells, b_text, ratio, row.target, met,
                     f"{rss / 1024:.0f} MB" if rss else "-"])
    widths = [max(len(str(r[i])) for r in [header, *rows]) for i in range(len(header))]
    lines = ["  ".join(str(c).ljust(w) for c, w in zip(r, widths)).rstrip() for r in [header, *rows]]
    lines.insert(1, "  ".join("-" * w for w in widths))
    mode = "quick (scaled-down sizes, 1 run)" if quick else f"full sizes, least CPU of {REPEATS} runs"
    lines.append("")
    lines.append(f"{mode}; CPU seconds of the run phase (parse + load for parse2000) in parentheses; "
                 "ratio = faultmas / python-agentspeak throughput.")
    interpreter = next((r.detail["interpreter"] for r in results.values() if "interpreter" in r.detail), None)
    if interpreter:
        lines.append(f"faultmas interpreter: {interpreter}"
                     + ("; from source: the same modules with FAULTMAS_PURE_PYTHON=1 (what runs without a C compiler)"
                        if source else ""))
    if baseline is None:
        lines.append(f"python-agentspeak baseline unavailable: {baseline_why}")
    lines.extend(f"FAILED {n}" for n in notes)
    return "\n".join(lines)


def run(quick: bool = False) -> str:
    """Measure every workload on faultmas and on python-agentspeak and return the side-by-side table."""
    if not (ASL_DIR / "README.md").exists():
        raise FileNotFoundError(f"{ASL_DIR}: the shared AgentSpeak benchmark programs are missing "
                                "(set FAULTMAS_ASL_BENCH_DIR)")
    repeats = 1 if quick else REPEATS
    python, why = baseline_python()
    startup = baseline_startup(python, repeats) if python else 0.0
    results: dict[str, Result] = {}
    source: dict[str, Result] = {}
    baseline: dict[str, Result] | None = {} if python else None
    for name, workload in WORKLOADS.items():
        results[name] = run_faultmas(workload, quick, repeats)
        if not results[name].detail.get("interpreter", "pure Python").startswith("pure"):
            source[name] = run_faultmas(workload, quick, repeats, from_source=True)
        if baseline is not None:
            # the full-size join costs python-agentspeak ~16 s CPU per run: once is enough to compare
            b_repeats = 1 if name == "beliefs" else repeats
            baseline[name] = run_baseline(python, workload, quick, b_repeats, startup)
    table = render(results, baseline, why, quick, source if len(source) == len(results) else None)
    if python:
        table += f"\npython-agentspeak start-up CPU subtracted: {startup:.3f} s ({python})"
    return table
