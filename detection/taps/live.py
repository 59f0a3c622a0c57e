"""What every live tap does the same way: stamp, record and feed messages in order, advance the clock
on a timer, sample processes for ``resource``, and turn graph or liveliness changes into ``@graph``
messages. A tap adds only its own I/O (subscriptions, graph queries)."""
from __future__ import annotations

import threading
import time
from typing import Callable

from detection.config import ObserverConfig
from detection.message import Message
from detection.observation import Observation
from detection.observer_set import ObserverSet
from detection.observers.activated import GRAPH_CHANNEL
from detection.observers.resource import RESOURCE_CHANNEL
from detection.taps.processes import ProcessSampler

RESOURCE_PERIOD = 0.5       # seconds between psutil samples


class LiveTap:
    def __init__(self, config: ObserverConfig, observers: ObserverSet,
                 on_observations: Callable[[list[Observation]], None], *, recorder=None,
                 clock: Callable[[], int] = time.time_ns) -> None:
        self.config = config
        self.observers = observers
        self.on_observations = on_observations
        self.recorder = recorder
        self.clock = clock
        self._lock = threading.Lock()      # callbacks may come from several threads (Zenoh)
        self._graph: frozenset[str] | None = None
        self._last_ns = 0
        self._last_resource = 0.0
        self._sampler = ProcessSampler(config.processes) if config.processes else None

    def begin(self) -> None:
        """Start the observers' clock (and the recording) now."""
        t0 = self.clock()
        with self._lock:
            self.observers.start(t0)
            if self.recorder is not None:
                self.recorder.start(t0)

    def feed(self, channel: str, raw: bytes | None = None, data=None, decode=None, msgtype: str | None = None,
             t_ns: int | None = None) -> None:
        """One message received at ``t_ns`` (default: now); the recording and the observers see it in
        the same order, on a clock that never goes back (a message taken late keeps its place)."""
        with self._lock:
            t_ns = max(self.clock() if t_ns is None else t_ns, self._last_ns)
            self._last_ns = t_ns
            msg = Message(channel, t_ns, data, raw, decode)
            if self.recorder is not None:
                self.recorder.write(msg, msgtype)
            changed = self.observers.feed(msg)
        if changed:
            self.on_observations(changed)

    def record(self, channel: str, t_ns: int, raw: bytes | None = None, data=None, msgtype: str | None = None) -> None:
        """Write a message no observer reads (another detector's: the learned one's topics and its
        ``@learned`` ticks) to the recording, if any, beside the observers' messages."""
        with self._lock:
            if self.recorder is not None:
                self.recorder.write(Message(channel, t_ns, data, raw), msgtype)

    def graph(self, names: frozenset[str]) -> None:
        """The nodes (or liveliness tokens) present now; fed to ``activated`` only when the set changes."""
        if self.config.nodes and names != self._graph:
            self._graph = names
            self.feed(GRAPH_CHANNEL, data=names)

    def tick(self) -> None:
        """Called on a timer: resource samples when due, then the evaluations due by now."""
        wall = time.monotonic()
        if self._sampler is not None and wall - self._last_resource >= RESOURCE_PERIOD:
            self._last_resource = wall
            for node, sample in self._sampler.sample().items():
                self.feed(RESOURCE_CHANNEL + node, data=sample)
        with self._lock:
            self._last_ns = max(self.clock(), self._last_ns)
            changed = self.observers.advance(self._last_ns)
        if changed:
            self.on_observations(changed)

    def close_recorder(self) -> None:
        with self._lock:
            if self.recorder is not None:
                self.recorder.stop(self._last_ns)
                self.recorder.close()
                self.recorder = None
