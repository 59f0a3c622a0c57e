"""``resource(node)``: the CPU share (% of one core) and resident memory (MB) of the node's process.

Fed by samples on the channel ``@resource/NODE`` (``data``: ``{"cpu": percent, "memory": megabytes}``),
which the tap reads with psutil a few times per second (or the learned detector of ``detection.learned``
replaces altogether by its own ``resource`` observations).
"""
from __future__ import annotations

from dataclasses import dataclass

from detection.message import Message
from detection.observers.base import Observer

RESOURCE_CHANNEL = "@resource/"


@dataclass
class ResourceObserver(Observer):
    kind = "resource"
    quantities = ("cpu", "memory")
    process: str = ""           # what identifies the process: a name or a command-line fragment

    def on_message(self, msg: Message) -> None:
        self.filters["cpu"].add(msg.field(("cpu",)))
        self.filters["memory"].add(msg.field(("memory",)))
