"""Wall-clock and memory limits for one ``faultmas diagnose`` run, in every phase.

Why: the search honours its ``Deadline`` (it stops and reports what it found, INCOMPLETE), but a run
also reads the model and builds the solver, and a search step in C (a cardinality encoding growing)
does not look at the clock. A 6,000-gate chain once ran 49 s under ``--timeout 5`` and took 3.3 GB.
Here one watcher thread samples the process's resident memory and the clock; past the memory
limit, or past the timeout plus a grace for the search to report on its own, it writes one line
naming the phase and the limit and ends the process with ``EXIT_LIMIT``. The process is ended, not
interrupted: a thread cannot interrupt C code, and memory must stop growing at once.

The resident size is read by psutil, but only once the process's peak resident size (``getrusage``, in
the standard library) has passed the limit: the current size is never above the peak, so a run that
stays below the limit never imports psutil (its import is a large part of a short run's start-up: issue 23).
"""
from __future__ import annotations

import io
import os
import resource
import sys
import threading
import time

#: Exit status of a run stopped by a limit (0: answered, 2: bad input).
EXIT_LIMIT = 3
#: Default ``--max-memory`` in MiB: far above what the ISCAS-85 circuits need (a few hundred MiB),
#: well below the machine (a run must not push the robot's other processes into swap).
DEFAULT_MAX_MEMORY_MB = 2048
#: Seconds past ``--timeout`` the search gets to stop by itself and report what it found.
GRACE = 1.0
POLL = 0.02
_MAXRSS_UNIT = 1 if sys.platform == "darwin" else 1024      # ru_maxrss: bytes on macOS, KiB on Linux


class RunLimits:
    """``with RunLimits(timeout, max_memory_mb) as limits: limits.phase("reading the model") ...``"""

    def __init__(self, timeout: float | None, max_memory_mb: float | None = DEFAULT_MAX_MEMORY_MB,
                 err: "io.TextIOBase | None" = None, prog: str = "faultmas diagnose") -> None:
        self.timeout = timeout
        self.max_bytes = None if max_memory_mb is None else int(max_memory_mb * 1024 * 1024)
        self.err = err or sys.stderr
        self.prog = prog
        self.started = time.monotonic()
        self.current = "starting"
        self.peak = 0
        self._done = threading.Event()
        self._process = None     # psutil.Process(), made once the peak passes the limit
        self._stopping = threading.Lock()  # one message, whichever thread finds the limit first
        self._thread = threading.Thread(target=self._watch, name="diagnose-limits", daemon=True)

    def __enter__(self) -> "RunLimits":
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._done.set()

    def phase(self, name: str) -> None:
        """Enter phase ``name``; the limits are checked here too (a run quicker than one poll is checked)."""
        self._check()
        self.current = name

    def left(self) -> float | None:
        """Seconds of the timeout left for the next phase (None: no timeout)."""
        if self.timeout is None:
            return None
        return max(0.0, self.timeout - (time.monotonic() - self.started))

    def _watch(self) -> None:
        while not self._done.wait(POLL):
            self._check()

    def _check(self) -> None:
        if self.max_bytes is not None:
            rss = self._resident_bytes()
            self.peak = max(self.peak, rss)
            if rss > self.max_bytes:
                self._stop(f"memory limit of {self.max_bytes // 2 ** 20} MiB exceeded while {self.current} "
                           f"(resident {rss // 2 ** 20} MiB); raise --max-memory, or bound the search "
                           f"with --max-card or --max-count")
        if self.timeout is not None and time.monotonic() > self.started + self.timeout + GRACE:
            self._stop(f"--timeout {self.timeout:g} s reached while {self.current}")

    def _resident_bytes(self) -> int:
        """The resident size now, or the peak so far while the peak is within the limit (then so is now)."""
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * _MAXRSS_UNIT
        if peak <= self.max_bytes:
            return peak
        if self._process is None:
            import psutil

            self._process = psutil.Process()
        return self._process.memory_info().rss

    def _stop(self, message: str) -> None:
        self._stopping.acquire()
        try:
            print(f"{self.prog}: {message}", file=self.err, flush=True)
        finally:
            os._exit(EXIT_LIMIT)
