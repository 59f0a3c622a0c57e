"""``FailureLog``: what a long-running loop or callback does with one of its own failures: contain it, say it
once, keep going, and know when it has become persistent.

Why: a thread that serves for hours (the simulator's, a tap's, a watchdog's) must not die of one exception
(issue 22: one SystemError out of OpenCV in one camera frame stopped the simulated world, and every robot went
blind while the run waited out its timeout), nor write one log line per frame or tick when the failure
repeats. So: the first failure of an episode is logged with its traceback; while it repeats, one line at 10,
100, 1000... failures in a row; the recovery is logged too. A new episode within ``quiet`` seconds of the last
line is counted, not logged, and the next line says how many were (nothing is lost silently: every failure is
counted in ``total``). ``consecutive`` lets the owner name a persistent failure (``persistent_after``), e.g. a
robot's camera reported failed.

Use: ``with failures.contained("frame at 3.20 s"): listener(frame)``, or ``failures.failed(exc, detail)`` and
``failures.succeeded()`` around code of one's own.
"""
from __future__ import annotations

import logging
import threading
import time
from contextlib import contextmanager
from typing import Callable, Iterator


class FailureLog:
    """The failures of one component (``what``, named in every line), logged to ``log`` without flooding it."""

    def __init__(self, log: logging.Logger, what: str, persistent_after: int = 10, quiet: float = 60.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.log, self.what = log, what
        self.persistent_after, self.quiet, self.clock = persistent_after, quiet, clock
        self.total = 0
        """Every failure, logged or not."""
        self.consecutive = 0
        """Failures since the last success."""
        self.last_error = ""
        """The last failure's ``repr`` (not the exception: its traceback would keep the failed call's frames and
        their data alive)."""
        self._total_at_line = 0
        """``total`` when the last line was written: the failures after it and before the one logged now were
        not logged one by one (those of the episode under way are told as "N times in a row")."""
        self._last_line = -float("inf")
        self._lock = threading.Lock()

    @property
    def persistent(self) -> bool:
        """Whether the component has failed ``persistent_after`` times in a row (and not succeeded since)."""
        return self.consecutive >= self.persistent_after

    @contextmanager
    def contained(self, detail: str = "") -> Iterator[None]:
        """Run the block; an ``Exception`` from it is counted and logged here, not raised (a success resets
        ``consecutive``). ``BaseException`` (KeyboardInterrupt, SystemExit) goes through."""
        try:
            yield
        except Exception as exc:
            self.failed(exc, detail)
        else:
            self.succeeded()

    def failed(self, exc: BaseException, detail: str = "") -> int:
        """Count one failure; log it if it starts an episode (and the log has been quiet) or is the 10th,
        100th... in a row. Returns the failures in a row."""
        with self._lock:
            self.total += 1
            self.consecutive += 1
            self.last_error = repr(exc)
            consecutive, now = self.consecutive, self.clock()
            first = consecutive == 1 and (self.total == 1 or now - self._last_line >= self.quiet)
            milestone = consecutive >= 10 and _power_of_ten(consecutive)
            became_persistent = consecutive == self.persistent_after
            if not (first or milestone or became_persistent):
                return consecutive
            unlogged = self.total - self._total_at_line - consecutive   # before this episode, after the last line
            self._total_at_line, self._last_line = self.total, now
        where = f" ({detail})" if detail else ""
        earlier = f"; {unlogged} earlier failures not logged one by one" if unlogged > 0 else ""
        if first:
            self.log.error("%s failed%s: %r; carrying on (%d failures in all%s)", self.what, where, exc,
                           self.total, earlier, exc_info=exc)
        else:
            self.log.error("%s failed %d times in a row%s%s: %r; carrying on (%d failures in all%s)", self.what,
                           consecutive, where, " (persistent now)" if became_persistent else "", exc,
                           self.total, earlier)
        return consecutive

    def succeeded(self) -> None:
        """The component worked: the episode of failures (if any) ends, with a line if it had become persistent."""
        if not self.consecutive:     # the common case, without the lock
            return
        with self._lock:
            consecutive, self.consecutive = self.consecutive, 0
            if consecutive < self.persistent_after:
                return
            self._last_line = self.clock()
        self.log.warning("%s works again after %d failures in a row (%d in all)", self.what, consecutive,
                         self.total)


def _power_of_ten(n: int) -> bool:
    while n % 10 == 0:
        n //= 10
    return n == 1
