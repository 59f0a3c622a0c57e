"""Wall-clock limits for queries: one shared watchdog thread interrupts the SAT solver when time is up.

A timer thread per query would be simplest, but starting a thread costs milliseconds on a loaded
machine, more than a whole query on a small circuit; the watchdog is started once and only told
about deadlines (a lock and a notify).
"""
from __future__ import annotations

import threading
import time

TYPE_CHECKING = False     # typing.TYPE_CHECKING without importing typing (issue 23: start-up)
if TYPE_CHECKING:
    from typing import Protocol

    class Interruptible(Protocol):
        def interrupt(self) -> None: ...
        def clear_interrupt(self) -> None: ...


class _Watchdog:
    """One daemon thread that interrupts each watched solver once its deadline has passed."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._watched: dict[int, tuple[float, Interruptible]] = {}
        self._thread: threading.Thread | None = None

    def watch(self, key: int, end: float, solver: Interruptible) -> None:
        with self._cond:
            self._watched[key] = (end, solver)
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="diagnosis-deadlines", daemon=True)
                self._thread.start()
            self._cond.notify()

    def release(self, key: int) -> None:
        """After this returns the solver is never interrupted for this key (it may be deleted)."""
        with self._cond:
            self._watched.pop(key, None)

    def _run(self) -> None:
        with self._cond:
            while True:
                now = time.monotonic()
                for key, (end, solver) in list(self._watched.items()):
                    if end <= now:
                        solver.interrupt()
                        del self._watched[key]
                soonest = min((end for end, _ in self._watched.values()), default=None)
                self._cond.wait(None if soonest is None else max(soonest - now, 0.0))


_WATCHDOG = _Watchdog()


class Deadline:
    """A wall-clock limit shared by the SAT calls of one query (None = no limit).

    ``watch(solver)`` has the solver interrupted when time is up, for the rest of the query;
    ``release(solver)`` ends that and clears a pending interrupt.
    """

    def __init__(self, seconds: float | None) -> None:
        self.end = None if seconds is None else time.monotonic() + seconds
        self._watching = False

    def left(self) -> float | None:
        return None if self.end is None else self.end - time.monotonic()

    def expired(self) -> bool:
        return self.end is not None and time.monotonic() >= self.end

    def watch(self, solver: Interruptible) -> "Deadline":
        if self.end is not None and not self._watching:
            self._watching = True
            _WATCHDOG.watch(id(self), self.end, solver)
        return self

    def release(self, solver: Interruptible) -> None:
        if self._watching:
            self._watching = False
            _WATCHDOG.release(id(self))
            solver.clear_interrupt()
