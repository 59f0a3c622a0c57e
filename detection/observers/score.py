"""``score(topic)``: a number field of the messages (a localisation score, a battery voltage...)."""
from __future__ import annotations

from dataclasses import dataclass

from detection.message import Message
from detection.observers.base import Observer


@dataclass
class ScoreObserver(Observer):
    kind = "score"
    quantities = ("score",)
    field_path: tuple[str, ...] = ("data",)

    def on_message(self, msg: Message) -> None:
        self.filters["score"].add(msg.field(self.field_path))
