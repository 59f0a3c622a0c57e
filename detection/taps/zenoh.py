"""The live Zenoh tap: a subscriber per topic key expression, liveliness tokens for ``activated``.

``ZenohKeys`` is the transport part, shared by every detector that listens on Zenoh: one session (its
own loopback peer, never multicast, or one given), raw payloads of key expressions and liveliness
changes handed to callbacks. ``ZenohTap`` feeds them to the observers; the learned detector
(``detection.learned.zenoh_events``) encodes them.

A configured topic ``/robot1/scan`` is the key expression ``robot1/scan``; payloads are decoded as JSON
only when an observer reads a field (``score``, ``movement``; ``timestamp`` reads ``header.stamp``).
``activated(node)`` holds while a liveliness token whose key is the node's name, or ends with
``/<name>``, is alive (e.g. ``faultmas/<mas>/alive/<agent>``). Samples of every key and liveliness changes are
handed over in the order they arrived (``ZenohKeys``), and the shared ``LiveTap`` keeps them in order with its timer.
"""
from __future__ import annotations

import json
import logging
import queue
import threading
import time
from typing import Any, Callable, Sequence

from detection.config import ObserverConfig
from detection.observation import Observation
from detection.observer_set import ObserverSet
from detection.taps.live import LiveTap
from robot_bridge.failure_log import FailureLog

INFO_KEY = "faultmas/observers/info"

log = logging.getLogger("faultmas.detection")


def zenoh_config(connect: Sequence[str] = (), listen: Sequence[str] = ()):
    """A peer on loopback unless told otherwise; never multicast scouting."""
    import zenoh

    config = zenoh.Config()
    config.insert_json5("mode", json.dumps("peer"))
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("listen/endpoints", json.dumps(list(listen) or ["tcp/127.0.0.1:0"]))
    if connect:
        config.insert_json5("connect/endpoints", json.dumps(list(connect)))
    return config


def key_of(topic: str) -> str:
    return topic.strip("/")


class ZenohKeys:
    """Raw samples on one Zenoh session: ``subscribe(key_expr, fn)`` calls ``fn(key, payload)``;
    ``liveliness(key_expr, fn)`` calls ``fn(key, alive)`` (history included). All on one thread of ours, in the
    order the samples arrived: zenoh-python runs each subscriber's callbacks on a thread of its own, so a request
    on one key and its answer on another were handed over the other way round (65 of 500 pairs 1 ms apart), and a
    ``timing(a, b)`` observer measured the delay to the *next* answer. Zenoh's own thread only queues each sample
    (not ``indirect``: a callback there sees the samples of all keys in arrival order)."""

    def __init__(self, *, session=None, connect: Sequence[str] = ()) -> None:
        import zenoh

        self._owns = session is None
        self.session = session if session is not None else zenoh.open(zenoh_config(connect))
        self._declared: list = []
        self._arrived: queue.SimpleQueue = queue.SimpleQueue()   # (handler, args), in arrival order; None: stop
        self._handing: threading.Thread | None = None

    def subscribe(self, key_expr: str, on_sample: Callable[[str, bytes], None]) -> None:
        self._declared.append(self.session.declare_subscriber(key_expr, self._queued(
            lambda sample: (on_sample, (str(sample.key_expr), sample.payload.to_bytes())))))

    def liveliness(self, key_expr: str, on_change: Callable[[str, bool], None]) -> None:
        import zenoh

        self._declared.append(self.session.liveliness().declare_subscriber(key_expr, self._queued(
            lambda sample: (on_change, (str(sample.key_expr), sample.kind == zenoh.SampleKind.PUT))), history=True))

    def _queued(self, call_for: Callable[[Any], tuple]) -> Any:
        """A Zenoh handler that queues ``call_for(sample)`` for the handing thread, on Zenoh's own thread."""
        import zenoh

        if self._handing is None:
            self._handing = threading.Thread(target=self._hand_over, daemon=True, name="faultmas-zenoh-keys")
            self._handing.start()
        return zenoh.handlers.Callback(lambda sample: self._arrived.put(call_for(sample)), indirect=False)

    def _hand_over(self) -> None:
        while (item := self._arrived.get()) is not None:
            handler, args = item
            try:
                handler(*args)
            except Exception:  # one bad sample must not stop the others
                log.exception("Zenoh tap: a sample on %s could not be handled", args[0])

    def publisher(self, key: str):
        pub = self.session.declare_publisher(key)
        self._declared.append(pub)
        return pub

    def close(self) -> None:
        for d in self._declared:
            try:
                d.undeclare()
            except Exception:       # already gone with the session
                pass
        self._declared = []
        if self._handing is not None:
            self._arrived.put(None)
            self._handing.join(5.0)
            self._handing = None
        if self._owns:
            self.session.close()


class ZenohTap(LiveTap):
    def __init__(self, config: ObserverConfig, observers: ObserverSet,
                 on_observations: Callable[[list[Observation]], None], *, session=None,
                 connect: Sequence[str] = (), clock: Callable[[], int] = time.time_ns) -> None:
        super().__init__(config, observers, on_observations, clock=clock)
        self.keys = ZenohKeys(session=session, connect=connect)
        self.session = self.keys.session
        self._alive: set[str] = set()
        self._tokens = threading.Lock()    # token changes come on Zenoh's threads: one at a time, in order
        self._stop = threading.Event()
        self._timer: threading.Thread | None = None

    def start(self) -> "ZenohTap":
        self.begin()
        for topic in self.config.topics:
            self.keys.subscribe(key_of(topic), lambda key, payload, t=topic: self.feed(t, raw=payload, decode=json.loads))
        if self.config.nodes:
            # nothing alive yet, said before the subscriber exists: its history may come at once on
            # another thread, and an empty graph said after it would hide those tokens until one changes
            self.graph(frozenset())
            self.keys.liveliness("**", self._on_token)
        self._timer = threading.Thread(target=self._ticks, daemon=True, name="faultmas-zenoh-tap")
        self._timer.start()
        return self

    def _on_token(self, key: str, alive: bool) -> None:
        with self._tokens:
            (self._alive.add if alive else self._alive.discard)(key)
            self.graph(frozenset(n for k in self._alive for n in ("/" + k, "/" + k.rsplit("/", 1)[-1])))

    def _ticks(self) -> None:
        period = 0.5 / max(self.config.rate_hz, 1.0)
        failures = FailureLog(log, "Zenoh tap: the observers' tick")   # one bad tick must not end the ticks
        while not self._stop.wait(period):
            with failures.contained():
                self.tick()

    def info_publisher(self, key: str = INFO_KEY):
        """A pipeline listener putting each ``Update`` as JSON on ``key``."""
        pub = self.keys.publisher(key)
        return lambda update: pub.put(json.dumps(update.to_json()))

    def close(self) -> None:
        self._stop.set()
        if self._timer is not None:
            self._timer.join(2.0)
        self.keys.close()
