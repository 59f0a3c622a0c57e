"""Shared set-up for the transport tests (imported explicitly; not a conftest): child processes that
run ``agents.transport.probe`` or ``agents.router`` with the venv's Python, and polling helpers."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path
from typing import Callable, Sequence

REPO = Path(__file__).resolve().parents[2]


def unique_mas(prefix: str = "t") -> str:
    """A MAS name no other test uses, so tests sharing a session never see each other."""
    return f"{prefix}{uuid.uuid4().hex[:8]}"


def poll(condition: Callable[[], object], timeout: float = 10.0, interval: float = 0.005) -> bool:
    """True as soon as ``condition()`` is truthy; False after ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(interval)
    return bool(condition())


class Child:
    """A child Python process that prints ``READY <endpoints>`` when it can be reached."""

    def __init__(self, args: Sequence[str], ready_prefix: str = "READY", ready_timeout: float = 30.0) -> None:
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self.process = subprocess.Popen([sys.executable, *args], cwd=REPO, env=env, text=True,
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        self.lines: list[str] = []
        self.errors: list[str] = []    # its standard error, read as it comes (a full pipe would stall it)
        self._new_line = threading.Condition()
        self._readers = [threading.Thread(target=self._read, daemon=True),
                         threading.Thread(target=self._read_errors, daemon=True)]
        for reader in self._readers:
            reader.start()
        ready = self.wait_line(ready_prefix, ready_timeout)
        if ready is None:
            self.stop()
            raise RuntimeError(f"child {args} not ready: {self.stderr[-2000:]}")
        self.endpoints: list[str] = (json.loads(ready.split(" ", 1)[1]) if ready.startswith("READY ")
                                     else ready.split(" listening on ", 1)[-1].split())

    def _read(self) -> None:
        for line in self.process.stdout:
            with self._new_line:
                self.lines.append(line.rstrip("\n"))
                self._new_line.notify_all()

    def _read_errors(self) -> None:
        for line in self.process.stderr:
            self.errors.append(line)

    @property
    def stderr(self) -> str:
        """What the child wrote on standard error so far (all of it once it has ended and been stopped)."""
        return "".join(self.errors)

    def wait_line(self, prefix: str, timeout: float = 30.0) -> str | None:
        """The first output line starting with ``prefix`` (waiting for it), or ``None``."""
        def found() -> str | None:
            return next((line for line in self.lines if line.startswith(prefix)), None)
        with self._new_line:
            self._new_line.wait_for(lambda: found() is not None or self.process.poll() is not None, timeout)
            return found()

    @property
    def pid(self) -> int:
        return self.process.pid

    def stop(self, timeout: float = 10.0, signum: int | None = None) -> int:
        """Close standard input (the polite stop) or send ``signum``, then kill if it lingers;
        the exit code."""
        try:
            self.process.stdin.close()
            if signum is not None and self.process.poll() is None:
                self.process.send_signal(signum)
        except OSError:
            pass
        try:
            code = self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            code = self.process.wait()
        for reader in self._readers:   # the pipes end with the process: the last lines are in
            reader.join(timeout=5)
        return code


def probe(mode: str, mas: str, name: str, connect: Sequence[str] = (), *extra: str) -> Child:
    args = ["-m", "agents.transport.probe", mode, "--mas", mas, "--name", name]
    for endpoint in connect:
        args += ["--connect", endpoint]
    return Child([*args, *extra])


def router(listen: str, *extra: str) -> Child:
    return Child(["-m", "agents.router", "--listen", listen, *extra], ready_prefix="faultmas router")
