"""Stopping child processes politely, then firmly: shared by ``faultmas ros launch`` and ``mas run --processes``."""
from __future__ import annotations

import signal
import subprocess
import time
from typing import Iterable, Sequence

ESCALATION: tuple[int, ...] = (signal.SIGINT, signal.SIGTERM, signal.SIGKILL)


def stop_processes(processes: Iterable[subprocess.Popen], grace: float,
                   signals: Sequence[int | None] = ESCALATION) -> None:
    """Send each signal in turn to the processes still running, waiting up to ``grace`` seconds after each.

    ``None`` in ``signals`` sends nothing and only waits (for children already asked to stop another way).
    """
    running = [p for p in processes if p.poll() is None]
    for signum in signals:
        running = [p for p in running if p.poll() is None]
        if not running:
            return
        if signum is not None:
            for proc in running:
                try:
                    proc.send_signal(signum)
                except ProcessLookupError:
                    pass
        deadline = time.monotonic() + grace
        for proc in running:
            try:
                proc.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                pass


def frozen(processes: dict[str, subprocess.Popen]) -> list[str]:
    """The names of the processes stopped now (SIGSTOP, a debugger): alive, yet doing nothing. A run that
    times out names them, so a freeze is not mistaken for slowness."""
    import psutil

    names = []
    for name, proc in processes.items():
        try:
            if proc.poll() is None and psutil.Process(proc.pid).status() in (psutil.STATUS_STOPPED,
                                                                            psutil.STATUS_TRACING_STOP):
                names.append(name)
        except psutil.Error:  # ended meanwhile
            pass
    return names
