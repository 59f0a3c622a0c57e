"""Shared helpers for the detection tests: files in a temporary folder, message streams at given rates."""
from __future__ import annotations

import signal
import subprocess
from pathlib import Path
from typing import Callable, Iterator

import pytest

from detection.message import Message

# The architecture the pipeline, CLI and agent tests share: a laser driver publishing scan, amcl using it.
NAV_MODEL = """\
architecture: nav
nodes:
  laser_driver: {pub: [scan]}
  amcl: {sub: [scan], pub: [pose]}
observations: [hz(scan), hz(pose)]
"""
# A rule that asks the agent `robot` to repair the laser driver when the scan is slow.
REPAIR_RULES = """\
rules:
  - name: ask_for_repair
    posObs: [~hz(scan)]
    posPosAb: [laser_driver]
    post: {agent: robot, literal: "+!repair(laser_driver)"}
"""


@pytest.fixture
def write(tmp_path: Path) -> Callable[[str, str], Path]:
    """write(name, text) -> path of a new file in the test's temporary folder."""
    def _write(name: str, text: str) -> Path:
        path = tmp_path / name
        path.write_text(text, encoding="utf-8")
        return path
    return _write


def stream(channel: str, rate_hz: float, start: float, end: float, data=None) -> Iterator[Message]:
    """Messages on ``channel`` at ``rate_hz`` from ``start`` to ``end`` seconds (``data(t)`` per message)."""
    n = 0
    while True:
        t = start + n / rate_hz
        if t >= end:
            return
        yield Message(channel, int(round(t * 1e9)), data(t) if data else None)
        n += 1


def merged(*streams: Iterator[Message]) -> list[Message]:
    return sorted((m for s in streams for m in s), key=lambda m: m.t_ns)


def interrupt(process: subprocess.Popen, timeout: float = 30.0) -> None:
    """Ctrl-C a command (``faultmas observe``) and wait for it to end cleanly; one still running after
    ``timeout`` is killed, so that the failing test leaves no process behind for the rest of the suite."""
    if process.poll() is not None:
        return
    process.send_signal(signal.SIGINT)
    try:
        process.wait(timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
        raise
