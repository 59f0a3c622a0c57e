"""Events that must reach an agent after the messages that came before them, though another subscriber brought them.

zenoh-python runs each subscriber's callbacks on a thread of its own, and an agent's inbox is drained by a thread
of ours: what two subscribers of one process receive in one order may be handled in the other. Zenoh itself keeps
the order of one link: when the control key's callback runs (a ``kill`` of agent b), or the liveliness
subscriber's (agent d has gone), every message sent before it is already in the Zenoh channel of its receiver's
inbox, or handed over. So the event is put *through* that channel: a marker, put on the inbox's key for this
session only (``Locality.SESSION_LOCAL``, it never leaves the process), queued behind those messages; the inbox
thread runs the event when it reaches the marker. A marker is known by its attachment, a secret of this process
and a number, so no other process can put one. An agent that leaves before its inbox reaches a marker releases it
(``release``): its inbox holds nothing more to wait for.
"""
from __future__ import annotations

import itertools
import logging
import secrets
import threading
from typing import Callable, Iterable

log = logging.getLogger("faultmas.transport")

_NUMBER = 8   # bytes of a marker's number, after the secret


class InboxBarriers:
    """Runs an action once each of some inboxes has handed over what it held when the action was asked for.
    ``put_marker(agent, attachment)`` queues a marker in ``agent``'s inbox (False: it has none now)."""

    def __init__(self, put_marker: Callable[[str, bytes], bool]) -> None:
        self._put_marker = put_marker
        self._secret = secrets.token_bytes(16)
        self._numbers = itertools.count(1)
        self._pending: dict[int, list] = {}           # number -> [inboxes still to reach it, action]
        self._waiting: dict[str, set[int]] = {}       # agent -> numbers its inbox has not reached yet
        self._lock = threading.Lock()

    def after(self, agents: Iterable[str], action: Callable[[], None]) -> None:
        """Run ``action`` (on the thread of the last inbox to get there, or now when there is none) once the inbox
        of each of ``agents`` has handed over every message it held now."""
        agents = list(dict.fromkeys(agents))
        number = next(self._numbers)
        with self._lock:
            self._pending[number] = [len(agents) + 1, action]   # +1: held until every marker is out
            for agent in agents:
                self._waiting.setdefault(agent, set()).add(number)
        attachment = self._secret + number.to_bytes(_NUMBER, "big")
        for agent in agents:
            if not self._put_marker(agent, attachment):
                self._reached(agent, number)
        self._reached(None, number)

    def is_marker(self, attachment: bytes | None) -> bool:
        return attachment is not None and len(attachment) == len(self._secret) + _NUMBER \
            and attachment.startswith(self._secret)

    def reached(self, agent: str, attachment: bytes) -> None:
        """``agent``'s inbox thread got to a marker (``is_marker``)."""
        self._reached(agent, int.from_bytes(attachment[len(self._secret):], "big"))

    def release(self, agent: str) -> None:
        """``agent`` left this process: the markers its inbox did not reach are reached (nothing is behind them)."""
        with self._lock:
            numbers = self._waiting.pop(agent, set())
        for number in numbers:
            self._count(number)

    def _reached(self, agent: str | None, number: int) -> None:
        if agent is not None:
            with self._lock:
                numbers = self._waiting.get(agent)
                if numbers is None or number not in numbers:
                    return   # released already
                numbers.discard(number)
                if not numbers:
                    del self._waiting[agent]
        self._count(number)

    def _count(self, number: int) -> None:
        with self._lock:
            entry = self._pending.get(number)
            if entry is None:
                return
            entry[0] -= 1
            if entry[0] > 0:
                return
            del self._pending[number]
        try:
            entry[1]()
        except Exception:  # an inbox thread must not die of an event's handler
            log.exception("an event handed over after an inbox failed")
