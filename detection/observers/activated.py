"""``activated(node)``: the node is present (ROS 2 graph) or its Zenoh liveliness token is alive.

Fed by graph messages: ``data`` is the set of node (or token) names present now, sent by the tap on
the channel ``@graph`` whenever the set changes (and recorded in a bag like any other message).
"""
from __future__ import annotations

from dataclasses import dataclass

from detection.message import Message
from detection.observers.base import Observer, Verdict

GRAPH_CHANNEL = "@graph"


@dataclass
class ActivatedObserver(Observer):
    kind = "activated"
    node: str = ""
    _present: bool | None = None

    def on_message(self, msg: Message) -> None:
        self._present = self.node in msg.data

    def evaluate(self, now_ns: int) -> Verdict | None:
        return None if self._present is None else Verdict(self._present, None, None)
