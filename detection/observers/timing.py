"""``timing(a, b)``: the delay from a message on topic A to the next message on topic B."""
from __future__ import annotations

from dataclasses import dataclass

from detection.message import Message
from detection.observers.base import Observer


@dataclass
class TimingObserver(Observer):
    kind = "timing"
    quantities = ("delay",)
    _pending_ns: int | None = None

    def on_message(self, msg: Message) -> None:
        if msg.channel == self.channels[0]:
            if self._pending_ns is None:
                self._pending_ns = msg.t_ns
        elif self._pending_ns is not None:
            self.filters["delay"].add((msg.t_ns - self._pending_ns) / 1e9)
            self._pending_ns = None
