"""No process that faultmas starts outlives the command that started it (a clean-clone ``make test`` once left a
``faultmas agent run ... faulty.asl`` of a ``faultmas run`` alive 30 minutes later): the command killed with
SIGKILL (no clean-up of its own can run) or stopped with SIGTERM (its clean-up runs), every descendant is gone
within seconds. Real commands, real agent and render processes."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

REPO = Path(__file__).resolve().parents[2]


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _start(tmp_path: Path, *argv: str) -> tuple[subprocess.Popen, Path]:
    """``faultmas ARGV`` started as a script's ``cmd &`` or a CI runner without job control starts it: SIGINT
    ignored (the clean-clone run that left the agent behind: the inspector's browser test stopped its ``faultmas
    run --inspect`` with SIGINT, ignored, then killed it after 30 s)."""
    log = tmp_path / "out.txt"
    with open(log, "w") as out:
        proc = subprocess.Popen([sys.executable, "-m", "agents", *argv], cwd=REPO, stdout=out, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, env=dict(os.environ, PYTHONUNBUFFERED="1"),
                                start_new_session=True, preexec_fn=_ignore_sigint)
    return proc, log


def _agents_started(proc: subprocess.Popen, names: set[str], log: Path, timeout: float = 120.0) -> list[psutil.Process]:
    """The command's descendants once an agent process runs for each of ``names``."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert proc.poll() is None, log.read_text()[-3000:]
        descendants = psutil.Process(proc.pid).children(recursive=True)
        running = set()
        for child in descendants:
            try:
                cmd = child.cmdline()
            except psutil.Error:
                continue
            if "--name" in cmd and cmd.index("--name") + 1 < len(cmd):
                running.add(cmd[cmd.index("--name") + 1])
        if names <= running:
            return descendants
        time.sleep(0.2)
    pytest.fail(f"agents {sorted(names)} not started within {timeout} s:\n{log.read_text()[-3000:]}")


def _still_alive(processes: list[psutil.Process], seconds: float) -> list[str]:
    start = time.monotonic()
    deadline = start + seconds
    alive = processes
    while time.monotonic() < deadline:
        alive = [p for p in alive if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
        if not alive:
            print(f"{len(processes)} descendants gone {time.monotonic() - start:.1f} s after", end=" ")
            return []
        time.sleep(0.1)
    return [" ".join(p.cmdline()[:6]) for p in alive if p.is_running()]


def _kill_all(processes: list[psutil.Process]) -> None:
    for p in processes:
        try:
            p.kill()
        except psutil.Error:
            pass


@pytest.mark.parametrize("signum", [signal.SIGKILL, signal.SIGTERM, signal.SIGINT])
def test_faultmas_run_leaves_no_process_behind(tmp_path, signum):
    proc, log = _start(tmp_path, "run", "--timeout", "120")
    descendants = []
    try:
        descendants = _agents_started(proc, {"faulty", "helper"}, log)
        time.sleep(1.0)                      # the agents past their start (Zenoh sessions open)
        descendants = psutil.Process(proc.pid).children(recursive=True)
        os.kill(proc.pid, signum)
        code = proc.wait(60)
        left = _still_alive(descendants, 10.0)
        print(f"{signal.Signals(signum).name} of faultmas run (SIGINT ignored at its start)")
        assert left == [], f"alive 10 s after {signal.Signals(signum).name} of faultmas run: {left}"
        if signum != signal.SIGKILL:         # stopped as by Ctrl-C, its clean-up ran (not killed by the signal)
            assert code >= 0, f"faultmas run ended by {signal.Signals(signum).name} without its clean-up ({code})"
    finally:
        if proc.poll() is None:
            proc.kill()
        _kill_all(descendants)


def test_mas_run_processes_leaves_no_process_behind(tmp_path):
    (tmp_path / "a.asl").write_text("!go.\n+!go <- .wait(100); !go.\n")
    (tmp_path / "t.mas2j").write_text("MAS orphans { agents: a #2; }\n")
    proc, log = _start(tmp_path, "mas", "run", str(tmp_path / "t.mas2j"), "--processes", "--timeout", "120")
    descendants = []
    try:
        descendants = _agents_started(proc, {"a1", "a2"}, log)
        time.sleep(1.0)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(30)
        assert _still_alive(descendants, 10.0) == []
        print("SIGKILL of faultmas mas run --processes")
    finally:
        if proc.poll() is None:
            proc.kill()
        _kill_all(descendants)


def test_faultmas_eval_pool_workers_end_with_it(tmp_path):
    proc, log = _start(tmp_path, "eval", "--runs", "4", "--jobs", "2", "--faults", "none", "--teams", "none")
    workers: list[psutil.Process] = []
    try:
        deadline = time.monotonic() + 60
        while len(workers) < 2 and time.monotonic() < deadline:
            assert proc.poll() is None, log.read_text()[-3000:]
            workers = psutil.Process(proc.pid).children(recursive=True)
            time.sleep(0.2)
        assert len(workers) >= 2, "no pool workers started"
        time.sleep(1.0)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(30)
        # the lifeline: SIGTERM, then SIGKILL 3 s later; a worker's sentinel is also held by the workers forked
        # after it, so they go one after the other
        assert _still_alive(workers, 20.0) == []
        print("SIGKILL of faultmas eval --jobs 2")
    finally:
        if proc.poll() is None:
            proc.kill()
        _kill_all(workers)
