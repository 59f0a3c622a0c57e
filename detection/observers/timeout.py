"""``timeout(topic)``: a message arrived within ``timeout`` seconds (counted from the start until the first)."""
from __future__ import annotations

from dataclasses import dataclass

from detection.message import Message
from detection.observers.base import Observer, Verdict


@dataclass
class TimeoutObserver(Observer):
    kind = "timeout"
    timeout: float = 1.0
    _last_ns: int | None = None
    _start_ns: int | None = None

    def start(self, t0_ns: int) -> None:
        self._start_ns = t0_ns

    def on_message(self, msg: Message) -> None:
        self._last_ns = msg.t_ns

    def evaluate(self, now_ns: int) -> Verdict | None:
        since = self._last_ns if self._last_ns is not None else self._start_ns
        if since is None:
            return None
        age = (now_ns - since) / 1e9
        return Verdict(age <= self.timeout, age, None)
