"""Messages held for other processes while the agents' thread is busy, then put together.

A Zenoh put costs ~5 µs of the caller's CPU plus a wake-up of Zenoh's sending thread, and the
receiver pays per sample too (a channel hand-over, a copy, a hand-over to the agent). An agent that
sends in a burst (a ``for`` loop of ``.send``) therefore holds its messages here, one batch per
receiver, and a batch goes out as ONE payload in the batch form of the envelope (``envelope.BATCH``:
the envelopes' JSON, one per line). A batch is sent when it reaches ``max_messages`` or
``max_bytes``, when its owner calls ``flush`` (the bridge does when the runtime goes idle, so a
question and its answer are not delayed) and at the latest ``max_delay`` seconds after it started
(a thread of ours, armed only when an empty outbox gets a message). Order per receiver is kept:
everything for one receiver goes through one list, put under one lock; a message that may not wait
(a question, an answer) first sends everything held, for every receiver.
"""
from __future__ import annotations

import logging
import threading
from typing import Callable

from agents.transport.envelope import BATCH_BYTES, BATCH_SEPARATOR

BATCH_MESSAGES = 256
"""Messages per batch at most (the receiver handles a batch before its agent runs)."""

BATCH_DELAY = 0.001
"""Seconds a held message waits at most when its owner does not flush (a busy runtime)."""

Put = Callable[[bytes], None]
log = logging.getLogger("faultmas.transport")


class _Batch:
    __slots__ = ("put", "payloads", "size")

    def __init__(self, put: Put) -> None:
        self.put = put
        self.payloads: list[bytes] = []
        self.size = 0

    def send(self) -> None:
        payloads = self.payloads
        self.put(payloads[0] if len(payloads) == 1 else BATCH_SEPARATOR.join(payloads))


class Outbox:
    """Held payloads by receiver; ``hold`` from any thread, ``flush`` from any thread."""

    def __init__(self, max_messages: int = BATCH_MESSAGES, max_bytes: int = BATCH_BYTES,
                 max_delay: float = BATCH_DELAY) -> None:
        self.max_messages = max_messages
        self.max_bytes = max_bytes
        self.max_delay = max_delay
        self._batches: dict[str, _Batch] = {}
        self._lock = threading.Lock()
        self._armed = threading.Event()
        self._stop: threading.Event | None = None  # set: the timer thread of now ends

    def hold(self, receiver: str, payload: bytes, put: Put, urgent: bool = False) -> None:
        """Queue ``payload`` for ``receiver`` (``put`` sends bytes to it); may send a full batch now.
        ``urgent``: send it now, after everything held (for any receiver: what was sent before a
        question is on its way before it), e.g. a question whose sender waits for the answer."""
        size = len(payload) + 1
        with self._lock:
            if urgent:
                self._send_all()
                put(payload)
                return
            batches = self._batches
            batch = batches.get(receiver)
            if batch is not None and batch.size + size > self.max_bytes:
                del batches[receiver]
                batch.send()
                batch = None
            if size > self.max_bytes:  # a big message goes alone (after what was held before it)
                put(payload)
                return
            if batch is None:
                batch = batches[receiver] = _Batch(put)
            batch.payloads.append(payload)
            batch.size += size
            if len(batch.payloads) >= self.max_messages:
                del batches[receiver]
                batch.send()
        if not self._armed.is_set():
            self._arm()

    def flush(self) -> None:
        """Send every held batch now."""
        if self._batches:  # read without the lock: a hold under way is flushed by the timer
            with self._lock:
                self._send_all()

    def _send_all(self) -> None:
        batches, self._batches = self._batches, {}
        for batch in batches.values():
            batch.send()

    def close(self) -> None:
        """Flush, and end the timer thread (a later ``hold`` starts another)."""
        self.flush()
        stop, self._stop = self._stop, None
        if stop is not None:
            stop.set()
            self._armed.set()

    def _arm(self) -> None:
        with self._lock:  # one timer thread, whichever threads hold
            if self._stop is None:
                self._stop = threading.Event()
                threading.Thread(target=self._flush_late, args=(self._stop,), daemon=True,
                                 name="faultmas-outbox").start()
        self._armed.set()

    def _flush_late(self, stop: threading.Event) -> None:
        """Flush ``max_delay`` after the first message of a batch, unless flushed by then."""
        armed, wait = self._armed.wait, threading.Event().wait
        while True:
            armed()
            if stop.is_set():
                return
            wait(self.max_delay)
            self._armed.clear()  # a hold from here on arms the next round
            try:
                self.flush()
            except Exception as exc:  # a put that fails (session closing) must not end the timer,
                # and must not go unnoticed: the held messages of that flush are gone
                log.warning("held messages could not be sent (late flush): %s", exc)
