"""Pause, step and resume one agent's reasoning cycle from another thread (the inspector's controls).

The gate runs inside the agent's own sense phase (as action feedback) and blocks its thread there, so
nothing of the agent moves while it is paused (its mailbox still fills: the network threads go on).
``step`` lets the blocked cycle finish; a timer due at once (the sense phase runs timers after the
feedback, in the same cycle) posts the gate as feedback again, which the NEXT cycle's sense phase
runs: exactly one reasoning cycle per step.
Agents of one ``LocalRuntime`` share a thread, so pausing one holds its process-mates too (with
``faultmas agent run`` each agent has its own process). A stop of the MAS releases the gate.
"""
from __future__ import annotations

import threading
import time
from typing import Any, Callable

POLL = 0.05
"""Seconds between checks of ``stopping`` while paused (signal handlers run in between)."""


class PauseGate:
    """Pause/step/resume ``agent``; ``stopping()`` true releases it for good (the MAS is stopping)."""

    def __init__(self, agent: Any, stopping: Callable[[], bool] = lambda: False) -> None:
        self.agent = agent
        self.stopping = stopping
        self._lock = threading.Lock()
        self._wanted = False       # the user wants the agent paused
        self._armed = False        # a gate is posted or waiting in the agent's thread
        self._blocked = threading.Event()   # the agent's thread waits in the gate now
        self._steps = 0            # cycles allowed to run before blocking again
        self._changed = threading.Condition(self._lock)

    @property
    def paused(self) -> bool:
        return self._wanted

    def pause(self, timeout: float = 5.0) -> bool:
        """Hold the agent at its next cycle; True once its thread is held (False: it did not cycle
        within ``timeout``, e.g. it is stopped; it will be held when it next runs)."""
        with self._lock:
            self._wanted = True
            arm = not self._armed
            self._armed = True
        if arm:
            self.agent.post_feedback(self._gate)
        return self._blocked.wait(timeout)

    def step(self, timeout: float = 5.0) -> bool:
        """Let a paused agent run exactly one reasoning cycle; True once it is held again."""
        with self._changed:
            if not self._wanted or not self._blocked.is_set():
                return False
            self._blocked.clear()
            self._steps += 1
            self._changed.notify_all()
        return self._blocked.wait(timeout)

    def resume(self) -> None:
        with self._changed:
            self._wanted = False
            self._changed.notify_all()

    def _rearm(self) -> None:
        """A timer of the stepped cycle: the feedback phase of this cycle is over, so the gate posted
        now runs in the next cycle's."""
        self.agent.post_feedback(self._gate)

    def _gate(self) -> None:
        """In the agent's thread: wait while paused; after a step, come back in the next cycle."""
        with self._changed:
            if not self._wanted:
                self._armed = False
                return
            self._blocked.set()
            held = time.monotonic()
            while self._wanted and self._steps == 0 and not self.stopping():
                self._changed.wait(POLL)
            self.agent.hold_timers(time.monotonic() - held)
            if self._steps and self._wanted:
                self._steps -= 1
                self.agent.add_timer(0.0, self._rearm)
                return
            self._blocked.clear()
            self._armed = False
            self._wanted = self._wanted and not self.stopping()
