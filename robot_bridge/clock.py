"""``FollowingClock``: an agent's clock that follows its robot's clock (a simulator's), as ROS 2 nodes with
``use_sim_time`` follow ``/clock``.

A simulator may run far slower than real time (twelve cameras on a loaded machine: 13 times slower) or
far faster (nothing to render). Plans written for a robot wait for robot time: ``.wait(300)`` for fresh
camera frames, three seconds for a helper to answer. Counted in wall time, those waits pass before the
simulated robot has moved at all, and helpers give up before they arrive. So an agent whose robot has a
clock counts its waits and timeouts in that clock (``agentspeak.agent.Agent.clock``).

The clock never stops an agent for good: while the source is gone (a simulator killed or frozen, a server
that publishes no clock, or no tick received yet) it runs on at wall pace after ``stale`` seconds, so no
``.wait`` waits forever. Whether the source is gone is ``alive()``'s to say when the owner knows (the
world's runner thread still stepping, however slowly; a server still sending ticks): a simulator that is
merely slow (a starved process may take seconds per step) or paused by its owner keeps the agents' time
standing, as ROS timers stand while Gazebo is paused. It is continuous and never goes backwards.
"""
from __future__ import annotations

import threading
import time
from typing import Callable

STALE_S = 15.0
"""Wall seconds the source may be gone before the clock runs on at wall pace: longer than a starved
process's scheduling gaps (a simulator step of a team took over 5 s at a load of 46 on 2 cores)."""


class FollowingClock:
    """Seconds that advance as ``source()`` does (``None``: no reading yet), and at wall pace once the source
    has been gone for ``stale`` wall seconds (from the start: until its first reading). Gone: ``alive()``
    is false, or, without ``alive``, no change of the reading. Thread-safe."""

    def __init__(self, source: Callable[[], float | None], stale: float = STALE_S,
                 wall: Callable[[], float] = time.monotonic, alive: Callable[[], bool] | None = None) -> None:
        self._source, self._stale, self._wall, self._alive = source, stale, wall, alive
        self._lock = threading.Lock()
        self._last: float | None = None      # the source's reading at its last change
        self._value = 0.0                    # this clock's value at that change
        self._changed_at = wall()            # wall time of that change (or of the start)
        self._alive_at = -float("inf")       # wall time ``alive()`` was last seen true

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
        """Whether the clock follows its source now (False: no reading yet, or running at wall pace)."""
        with self._lock:
            return self._last is not None and self._free_run(self._wall()) == 0.0

    def _free_run(self, now: float) -> float:
        """Seconds gained at wall pace since the last change: all of them before the first reading, those
        beyond ``stale`` after it."""
        if self._last is None:
            return now - self._changed_at
        if self._alive is not None and self._alive():
            self._alive_at = now
            return 0.0
        return max(0.0, now - max(self._changed_at, self._alive_at) - self._stale)
