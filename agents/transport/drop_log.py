"""The log lines of dropped messages, rate-limited per reason so that a flood cannot flood the log.

Why: one 63 KB network message can be a batch of 21,000 tiny bad envelopes; a line per drop made that
21,000 warning lines (log amplification: disk, terminal and the operator's attention). Here the first
``burst`` drops of each reason in a window of ``window`` seconds get their own line, as before; the rest
of the window is counted and summed up in one line when the window ends ("... and 20,995 more"), with
the senders named. Nothing is dropped silently: every drop is either on its own line or in a summary,
and the transport's ``dropped`` counters count each one.
"""
from __future__ import annotations

import logging
import threading
import time
from collections import Counter
from dataclasses import dataclass, field


@dataclass
class _Window:
    started: float
    logged: int = 0
    suppressed: int = 0
    senders: Counter = field(default_factory=Counter)
    where: set = field(default_factory=set)


class DropLog:
    """``drop(reason, where, sender, detail)`` logs a line or counts it into the reason's summary."""

    #: senders and places named in a summary (hostile input cannot make a summary line long)
    NAMED = 5

    def __init__(self, log: logging.Logger, burst: int = 10, window: float = 10.0,
                 clock=time.monotonic) -> None:
        self.log = log
        self.burst = burst
        self.window = window
        self.clock = clock
        self._windows: dict[str, _Window] = {}
        self._lock = threading.Lock()
        self._timer: threading.Timer | None = None

    def drop(self, reason: str, where: str, sender: str | None, detail: str = "") -> None:
        now = self.clock()
        with self._lock:
            window = self._windows.get(reason)
            if window is not None and now - window.started >= self.window:
                self._summarise(reason, window)
                window = None
            if window is None:
                window = self._windows[reason] = _Window(now)
            if window.logged < self.burst:
                window.logged += 1
                suppress = False
            else:
                window.suppressed += 1
                if len(window.senders) < 1000 or sender in window.senders:
                    window.senders[sender or "unknown sender"] += 1
                if len(window.where) < self.NAMED:
                    window.where.add(where)
                suppress = True
                self._start_timer()
        if not suppress:
            self.log.warning("dropped message on %s from %s: %s%s", where, sender or "unknown sender", reason,
                             f" ({detail})" if detail else "")
            if window.logged == self.burst:
                self.log.warning("more drops for %s in the next %.0f s are counted and summed up in one line",
                                 reason, self.window)

    def flush(self) -> None:
        """Write the summary of every window that suppressed something (at the window's end, and on close)."""
        with self._lock:
            for reason, window in list(self._windows.items()):
                self._summarise(reason, window)
            self._windows.clear()

    def _summarise(self, reason: str, window: _Window) -> None:
        if window.suppressed:
            top = ", ".join(f"{name} ({count})" for name, count in window.senders.most_common(self.NAMED))
            more = len(window.senders) - self.NAMED
            self.log.warning("dropped %d more messages for %s on %s in %.0f s (not logged one by one); from %s%s",
                             window.suppressed, reason, ", ".join(sorted(window.where)), self.window, top,
                             f" and {more} other senders" if more > 0 else "")
            window.suppressed = 0
            window.senders.clear()

    def _start_timer(self) -> None:
        """One timer at a time writes the summaries when the windows end (a flood that stops is summed up)."""
        if self._timer is None or not self._timer.is_alive():
            self._timer = threading.Timer(self.window, self._on_timer)
            self._timer.daemon = True
            self._timer.start()

    def _on_timer(self) -> None:
        now = self.clock()
        with self._lock:
            pending = False
            for reason, window in list(self._windows.items()):
                if now - window.started >= self.window:
                    self._summarise(reason, window)
                    del self._windows[reason]
                elif window.suppressed:
                    pending = True
            self._timer = None
            if pending:
                self._start_timer()
