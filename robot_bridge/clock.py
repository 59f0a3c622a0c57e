"""``FollowingClock``: an agent's clock that follows its robot's clock (a simulator's), as ROS 2 nodes with
``use_sim_time`` follow ``/clock``.

A simulator may run far slower than real time (twelve cameras on a loaded machine: 13 times slower) or
far faster (nothing to render). Plans written for a robot wait for robot time: ``.wait(300)`` for fresh
camera frames, three seconds for a helper to answer. Counted in wall time, those waits pass before the
simulated robot has moved at all, and helpers give up before they arrive. So an agent whose robot has a
clock counts its waits and timeouts in that clock (``agentspeak.agent.Agent.clock``).

The clock never stops an agent: while the source is silent (a simulator killed or frozen, a server that
publishes no clock, or no tick received yet) it runs on at wall pace after ``stale`` seconds, so no
``.wait`` waits forever. It is continuous and never goes backwards, whatever the source does.
"""
from __future__ import annotations

import threading
import time
from typing import Callable

STALE_S = 5.0
"""Wall seconds without a tick of the source after which the clock runs on at wall pace. Longer than any
single simulator step takes under load (a step renders every camera that is due: ~1 s seen at load 40)."""


class FollowingClock:
    """Seconds that advance as ``source()`` does (``None``: no reading yet), and at wall pace while it does not
    change for more than ``stale`` wall seconds (from the start: until its first reading). Thread-safe."""

    def __init__(self, source: Callable[[], float | None], stale: float = STALE_S,
                 wall: Callable[[], float] = time.monotonic) -> None:
        self._source, self._stale, self._wall = source, stale, wall
        self._lock = threading.Lock()
        self._last: float | None = None      # the source's reading at its last change
        self._value = 0.0                    # this clock's value at that change
        self._changed_at = wall()            # wall time of that change (or of the start)

    def __call__(self) -> float:
        reading = self._source()
        now = self._wall()
        with self._lock:
            free = self._free_run(now)
            if reading is not None and reading != self._last:
                step = 0.0 if self._last is None else max(0.0, reading - self._last)
                self._value += max(free, step)   # what the source did during a stall was already given
                self._last, self._changed_at = reading, now
                return self._value
            return self._value + free

    @property
    def following(self) -> bool:
        """Whether the source has ticked within ``stale`` wall seconds (False: running at wall pace)."""
        with self._lock:
            return self._last is not None and self._wall() - self._changed_at <= self._stale

    def _free_run(self, now: float) -> float:
        """Seconds gained at wall pace since the last change: all of them before the first reading, those
        beyond ``stale`` after it."""
        if self._last is None:
            return now - self._changed_at
        return max(0.0, now - self._changed_at - self._stale)
