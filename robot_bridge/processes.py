"""Stopping child processes politely, then firmly: shared by ``faultmas ros launch`` and ``mas run --processes``."""
from __future__ import annotations

import signal
import subprocess
import threading
import time
from typing import Callable, Iterable, Sequence

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
    """The names of the processes stopped now (SIGSTOP, a debugger): alive, yet doing nothing."""
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


class FreezeWatch:
    """Samples ``processes()`` every ``interval`` seconds in a thread of its own and adds up how long each was
    stopped (SIGSTOP): a run that goes wrong or times out names the processes that froze, even if they were
    continued since (a freeze explains a timeout that slowness would not)."""

    def __init__(self, processes: Callable[[], dict[str, subprocess.Popen]], interval: float = 0.5) -> None:
        self.processes = processes
        self.interval = interval
        self.stopped_seconds: dict[str, float] = {}
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True, name="faultmas-freeze-watch")

    def __enter__(self) -> "FreezeWatch":
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._done.set()
        self._thread.join(5.0)

    def _watch(self) -> None:
        while not self._done.wait(self.interval):
            for name in frozen(self.processes()):
                self.stopped_seconds[name] = self.stopped_seconds.get(name, 0.0) + self.interval

    def report(self) -> list[tuple[str, float]]:
        """(name, seconds seen stopped) of every process that froze, frozen now or not."""
        return sorted(self.stopped_seconds.items())
