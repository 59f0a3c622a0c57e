"""The test session checks that it leaves no process behind (issue 22: a clean-clone ``make test`` once left a
``faultmas agent run ... faulty.asl`` alive 30 minutes later).

Every process a test starts inherits ``FAULTMAS_TEST_SESSION`` (a token of this session) from the environment,
unless the test gives its child an environment of its own; at the end of the session any process still
carrying the token is a leftover: it gets ``LEFTOVER_GRACE`` seconds to end, then is named (pid, command, age),
killed, and the session fails. Matching on the token, not on the command, keeps another session in the same
checkout (or another engineer's) out of the count.

Under pytest-xdist (``make test`` runs two workers) the workers inherit the controller's token and keep it, so
every process a test starts carries it; the controller checks once, after its workers have ended."""
from __future__ import annotations

import os
import secrets
import sys
import time

import pytest

SESSION_ENV = "FAULTMAS_TEST_SESSION"
LEFTOVER_GRACE = 15.0      # seconds a process of the session gets to end after the last test (a slow shutdown)
_token = secrets.token_hex(8)
_leftovers: list[str] = []


def _is_xdist_worker(config) -> bool:
    return hasattr(config, "workerinput")


def pytest_sessionstart(session) -> None:
    if not _is_xdist_worker(session.config):   # a worker keeps the controller's token (inherited)
        os.environ[SESSION_ENV] = _token


def _session_processes() -> list:
    import psutil

    me, found = os.getpid(), []
    for proc in psutil.process_iter():
        try:
            if proc.pid != me and proc.status() != psutil.STATUS_ZOMBIE \
                    and proc.environ().get(SESSION_ENV) == _token:
                found.append(proc)
        except psutil.Error:      # gone meanwhile, or not ours to read
            pass
    return found


@pytest.hookimpl(trylast=True)     # under xdist: after xdist's own, which ends the workers
def pytest_sessionfinish(session, exitstatus) -> None:
    import psutil

    worker = _is_xdist_worker(session.config)
    if os.environ.get(SESSION_ENV) != _token and not worker:
        return
    render_processes = sys.modules.get("robot_bridge.sim.render_processes")
    if render_processes is not None:      # this process's own render workers live until its exit: end them first
        render_processes.close_shared_pool()
    if worker:                            # the other worker's processes carry the token too: the controller checks
        return
    deadline = time.monotonic() + LEFTOVER_GRACE
    left = _session_processes()
    while left and time.monotonic() < deadline:
        time.sleep(0.5)
        left = _session_processes()
    for proc in left:
        try:
            _leftovers.append(f"pid {proc.pid}, up {time.time() - proc.create_time():.0f} s: "
                              + " ".join(proc.cmdline())[:300])
            proc.kill()
        except psutil.Error:
            pass
    if _leftovers and session.exitstatus == 0:
        session.exitstatus = 1


def pytest_terminal_summary(terminalreporter) -> None:
    if _leftovers:
        terminalreporter.section("processes left behind by the tests (killed now)", red=True, bold=True)
        for line in _leftovers:
            terminalreporter.line(line)
