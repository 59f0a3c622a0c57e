"""What the bridges that talk to a robot by messages share (``Ros2Bridge``, ``ZenohBridge``).

``PendingActions``: actions sent and not answered yet; each fails with ``timeout`` when its answer is
late and with ``shutdown`` when the bridge closes, so no agent waits forever. ``PerceptStore``: the
percepts received in the jason_ros wire format (single percepts and per-source snapshots with a
time to live), so a silent sensor's percepts disappear.
"""
from __future__ import annotations

import threading
import time
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Callable

from robot_bridge import actions
from robot_bridge.protocol import Action, Completion, Percept

ANSWER_MARGIN_S = 3.0
"""How much longer than the motion's own time bound a bridge waits for the robot's answer."""


def answer_timeout(action: Action, margin: float = ANSWER_MARGIN_S) -> float:
    """Seconds to wait for the status of a (valid) action before failing it with ``timeout``."""
    from robot_bridge.sim import motion
    from robot_bridge.sim.odometry import Odometry

    spec, args = actions.normalize(action)
    if spec.motion:
        bound = motion.start(spec.name, args, Odometry(), 0.0, (0.7, 3.0))
        return bound.deadline + margin
    return margin


def resolve(future: "Future[Completion]", completion: Completion) -> None:
    """Resolve ``future`` unless something else already did."""
    if not future.done():
        try:
            future.set_result(completion)
        except Exception:         # resolved concurrently
            pass


@dataclass
class _Pending:
    action: Action
    future: "Future[Completion]"
    deadline: float


class PendingActions:
    """Futures by action id, each with a deadline on ``clock`` (seconds; the robot's clock when it has one:
    a simulated motion's time bound is in simulated time; default wall time). Thread-safe."""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._items: dict[int, _Pending] = {}
        self._lock = threading.Lock()
        self._clock = clock

    def add(self, action: Action, limit_s: float) -> "Future[Completion]":
        future: Future[Completion] = Future()
        with self._lock:
            self._items[action.id] = _Pending(action, future, self._clock() + limit_s)
        return future

    def finish(self, action_id: int, completion: Completion) -> bool:
        """Resolve action ``action_id``; False when it is unknown (already answered or expired)."""
        with self._lock:
            item = self._items.pop(action_id, None)
        if item is None:
            return False
        resolve(item.future, completion)
        return True

    def expire(self, who: str) -> None:
        """Fail every action whose answer is overdue with ``timeout``, naming ``who`` was silent."""
        now = self._clock()
        with self._lock:
            late = [self._items.pop(i) for i, p in list(self._items.items()) if p.deadline <= now]
        for item in late:
            resolve(item.future, Completion.failure("timeout", f"{who} did not answer {item.action} in time"))

    def fail_all(self, reason: str) -> None:
        with self._lock:
            items, self._items = list(self._items.values()), {}
        for item in items:
            resolve(item.future, Completion.failure(reason, f"{item.action} still running"))

    def __len__(self) -> int:
        return len(self._items)


class PerceptStore:
    """The latest percepts received as wire messages (see ``robot_bridge.ros2.wire``). Thread-safe."""

    def __init__(self, agent_name: str) -> None:
        self.agent_name = agent_name
        self._single: dict[tuple[str, int], list[Percept]] = {}
        self._snapshots: dict[str, tuple[tuple[Percept, ...], float]] = {}
        self._lock = threading.Lock()
        self.received = threading.Event()
        """Set once anything for this agent has arrived (bridges wait on it in ``setup``)."""

    def receive(self, text: str) -> None:
        """Store a percept message; raises ``wire.WireError`` (quoting it) when it is malformed."""
        from robot_bridge.ros2 import wire

        data = wire.decode_percepts(text)
        if data.agent_name not in ("", self.agent_name):
            return
        if isinstance(data, wire.PerceptSnapshot):
            expires = time.monotonic() + data.ttl if data.ttl is not None else float("inf")
            with self._lock:
                self._snapshots[data.source] = (data.percepts, expires)
        else:
            self.store(data.percept(), data.update)
        self.received.set()

    def store(self, percept: Percept, update: bool = True) -> None:
        """``update``: replace percepts with the same name and arity; else add to them."""
        key = (percept.name, len(percept.args))
        with self._lock:
            if update:
                self._single[key] = [percept]
            elif percept not in self._single.setdefault(key, []):
                self._single[key].append(percept)

    def percepts(self) -> list[Percept]:
        now = time.monotonic()
        with self._lock:
            result = [p for group in self._single.values() for p in group]
            for source, (items, expires) in list(self._snapshots.items()):
                if expires < now:
                    del self._snapshots[source]
                else:
                    result.extend(items)
        return result
