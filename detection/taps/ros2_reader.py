"""Taking messages from ROS 2 cheaply: raw subscriptions read by one thread of our own, in batches.

The one way faultmas receives ROS 2 messages it watches (the observers' ``Ros2Tap``, the learned
detector's ``RawTap`` and its recorder all sit on a ``TopicReader``). Why not rclpy's executor: its
Python bookkeeping costs ~150 µs per message (measured: 10 topics at 1,000 msgs/s in total took 9.4 %
of a core with raw subscriptions and empty callbacks, against 1.6-2.3 % for this reader, of which
~60 % is Fast DDS's own receive thread). The reader waits on an rcl wait set, drains every ready
subscription completely, then sleeps ``batch`` seconds so that one wake-up takes many messages
(each keeps the time the middleware received it, so batching does not blur timing). Messages stay
serialized (CDR bytes): deserializing is the user's choice, per field, when needed. They are taken
with one copy into a buffer kept between takes (``ros2_take``), and a topic whose every consumer
needs only a message's first bytes (``subscribe(head=N)``) gets ``MessageHead``s of big messages.

The subscriptions live on a node of their own that no executor spins (an executor would take the
messages first); it shares the caller's rclpy context, so one DDS participant serves both.
"""
from __future__ import annotations

import logging
import threading
import time
from typing import Callable

from robot_bridge.failure_log import FailureLog

log = logging.getLogger("faultmas.detection")

Batch = list[tuple[int, str, bytes]]
"""``(receive time in ns, topic, CDR bytes)``, sorted by receive time (the bytes are a
``ros2_take.MessageHead`` for a topic subscribed with ``head`` by all its consumers)."""

BATCH_S = 0.02          # after a wake-up, let messages gather this long (at 1,000 msgs/s: ~20 per wake-up)


class _Listener:
    """One consumer of a shared reader: its topics (None: all), its batch callback and its own tick."""

    def __init__(self, on_batch, topics, on_tick, tick_s: float) -> None:
        self.on_batch, self.on_tick, self.tick_s = on_batch, on_tick, tick_s
        self.topics: set[str] | None = None if topics is None else set(topics)
        self.next_tick = time.monotonic() + tick_s
        self.failures = FailureLog(log, f"ROS 2 reader: consumer {getattr(on_batch, '__qualname__', on_batch)!s}")
        """One consumer that raises loses that batch or tick, not the reader the others share."""


class TopicReader:
    """Raw subscriptions on a private node, read by one thread that calls ``on_batch(batch)`` with
    what arrived and ``on_tick()`` every ``tick_s`` seconds (both on that thread, so a user needs
    no lock between them).

    Several consumers may share one reader (``add_listener``): the observers and the learned detector
    of ``faultmas observe CONFIG --learned`` then take each topic through one subscription, so Fast DDS
    receives a message once, not once per consumer (its receive thread is most of the CPU spent)."""

    def __init__(self, context, on_batch: Callable[[Batch], None] | None = None, *,
                 on_tick: Callable[[], None] | None = None, tick_s: float = 1.0, batch_s: float = BATCH_S,
                 name: str = "faultmas_reader") -> None:
        import rclpy.node
        from rclpy.guard_condition import GuardCondition

        self.context = context
        self.node = rclpy.node.Node(name, context=context, start_parameter_services=False)
        self.batch_s = batch_s
        self.received = 0
        self._listeners: list[_Listener] = []
        self._subscriptions: dict[str, object] = {}
        self._heads: dict[str, int | None] = {}     # topic -> bytes its consumers need (None: whole messages)
        self._changed = True
        self._stop = threading.Event()
        self._wake = GuardCondition(None, None, context=context)
        self._thread: threading.Thread | None = None
        if on_batch is not None or on_tick is not None:
            self.add_listener(on_batch or (lambda _batch: None), on_tick=on_tick, tick_s=tick_s)

    @property
    def on_batch(self) -> Callable[[Batch], None]:
        """The first listener's batch callback (a benchmark wraps it to time it)."""
        return self._listeners[0].on_batch

    @on_batch.setter
    def on_batch(self, function: Callable[[Batch], None]) -> None:
        self._listeners[0].on_batch = function

    @property
    def on_tick(self) -> Callable[[], None] | None:
        return self._listeners[0].on_tick

    @on_tick.setter
    def on_tick(self, function: Callable[[], None] | None) -> None:
        self._listeners[0].on_tick = function

    def add_listener(self, on_batch: Callable[[Batch], None], *, topics=None,
                     on_tick: Callable[[], None] | None = None, tick_s: float = 1.0, batch_s: float | None = None):
        """Another consumer: ``on_batch`` gets the messages of ``topics`` (None: every topic), ``on_tick``
        runs every ``tick_s`` seconds, on the reader's thread like the others. ``batch_s``: the longest
        it may wait for a batch (the reader takes the smallest its listeners ask for)."""
        listener = _Listener(on_batch, topics, on_tick, tick_s)
        self._listeners = [*self._listeners, listener]          # the thread iterates over a snapshot
        if batch_s is not None:
            self.batch_s = min(self.batch_s, batch_s)
        self._wake.trigger()
        return listener

    def remove_listener(self, listener: _Listener) -> None:
        """``listener`` gets nothing more (its topics stay subscribed: another listener may read them)."""
        self._listeners = [l for l in self._listeners if l is not listener]

    def listen_to(self, listener: _Listener, topic: str) -> None:
        """``listener`` (of ``add_listener``) gets ``topic`` too (a topic subscribed once discovered)."""
        if listener.topics is not None:
            listener.topics = listener.topics | {topic}

    def subscribe(self, topic: str, msg_class: type, depth: int = 100, *, head: int | None = None) -> None:
        """Take ``topic``'s messages (best effort: matches every publisher; ``depth`` messages are kept
        between two wake-ups, 100 ms of a 1 kHz topic at the default). A topic already taken keeps its
        one subscription (another listener's), whoever asks again.

        ``head``: this consumer needs only the first ``head`` bytes of a message and its size; a longer
        message then comes as a ``MessageHead`` (its pixels, say, are never copied), unless another
        consumer of the topic asked for whole messages: then every consumer gets them whole."""
        from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

        if topic in self._heads:
            wanted = self._heads[topic]
            self._heads[topic] = None if head is None or wanted is None else max(wanted, head)
        else:
            self._heads[topic] = head
        if topic in self._subscriptions:
            return
        qos = QoSProfile(depth=depth, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.BEST_EFFORT)
        self._subscriptions[topic] = self.node.create_subscription(msg_class, topic, lambda _raw: None, qos,
                                                                   raw=True)   # taken by the thread, never called
        self._changed = True
        self._wake.trigger()

    @property
    def topics(self) -> list[str]:
        return list(self._subscriptions)

    def start(self) -> "TopicReader":
        """Start the thread (once: a second consumer's ``start`` is a no-op)."""
        if self._thread is None:
            self._thread = threading.Thread(target=self._loop, daemon=True, name="faultmas-ros2-reader")
            self._thread.start()
        return self

    def close(self) -> None:
        """Stop the thread (after the batch it is handling) and destroy the node; idempotent."""
        if self._stop.is_set():
            return
        self._stop.set()
        if self._thread is not None:
            self._wake.trigger()
            self._thread.join(5.0)
        self.node.destroy_node()

    # -- the reader's thread --------------------------------------------------------------------------
    def _loop(self) -> None:
        from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

        from detection.taps.ros2_take import Taker

        wait_set, subs = None, []
        taker = Taker.create()
        try:
            while not self._stop.is_set() and self.context.ok():
                if self._changed or wait_set is None:
                    self._changed = False
                    subs = list(self._subscriptions.items())
                    with self.context.handle:
                        wait_set = _rclpy.WaitSet(len(subs), 1, 0, 0, 0, 0, self.context.handle)
                listeners = self._listeners
                next_tick = min((l.next_tick for l in listeners), default=time.monotonic() + 1.0)
                wait_set.clear_entities()
                for _topic, sub in subs:
                    wait_set.add_subscription(sub.handle)
                wait_set.add_guard_condition(self._wake.handle)
                wait_set.wait(max(0, int((next_tick - time.monotonic()) * 1e9)))
                ready = set(wait_set.get_ready_entities("subscription"))
                batch: Batch = []
                for topic, sub in subs:
                    if sub.handle.pointer in ready:
                        self._drain(topic, sub, batch, taker, self._heads.get(topic))
                if batch:
                    batch.sort(key=lambda m: m[0])
                    self.received += len(batch)
                    for listener in listeners:
                        mine = batch if listener.topics is None else [m for m in batch if m[1] in listener.topics]
                        if mine:
                            with listener.failures.contained(f"a batch of {len(mine)} messages"):
                                listener.on_batch(mine)
                now = time.monotonic()
                for listener in listeners:
                    if now >= listener.next_tick:
                        listener.next_tick = now + listener.tick_s
                        if listener.on_tick is not None:
                            with listener.failures.contained("its tick"):
                                listener.on_tick()
                if batch:
                    self._stop.wait(self.batch_s)
        except Exception:
            if self.context.ok() and not self._stop.is_set():       # not a shutdown under our feet
                log.exception("ROS 2 reader stopped")
        finally:
            if taker is not None:
                taker.close()

    @staticmethod
    def _drain(topic: str, sub, out: Batch, taker=None, head: int | None = None) -> None:
        """Every message waiting on ``sub``, with the time the middleware received it (by ``taker``,
        a ``ros2_take.Taker``, when there is one, else through rclpy)."""
        with sub.handle:
            if taker is not None:
                taker.drain(sub.handle.pointer, topic, head, out)
                return
            take, cls = sub.handle.take_message, sub.msg_type
            while (taken := take(cls, True)) is not None:
                out.append((taken[1].get("received_timestamp") or time.time_ns(), topic, taken[0]))
