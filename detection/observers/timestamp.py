"""``timestamp(topic)``: the age of a message when it arrives, receive time - ``header.stamp``.

From raw CDR bytes the stamp is read in place (encapsulation header, then ``int32 sec, uint32 nanosec``:
the first field of every stamped message), without deserializing the message.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass

from detection.message import Message, MessageError
from detection.observers.base import Observer

_LE = struct.Struct("<iI")
_BE = struct.Struct(">iI")


def header_stamp_ns(msg: Message) -> int:
    """``header.stamp`` in ns, from the raw CDR bytes when present, else from the decoded message."""
    raw = msg.raw
    if raw is not None:
        if len(raw) < 12:
            raise MessageError(f"{msg.channel}: message too short for a header stamp ({len(raw)} bytes)")
        sec, nsec = (_LE if raw[1] & 1 else _BE).unpack_from(raw, 4)
        return sec * 1_000_000_000 + nsec
    return int(msg.field(("header", "stamp", "sec"))) * 1_000_000_000 + int(msg.field(("header", "stamp", "nanosec")))


@dataclass
class TimestampObserver(Observer):
    kind = "timestamp"
    quantities = ("delay",)

    def on_message(self, msg: Message) -> None:
        self.filters["delay"].add((msg.t_ns - header_stamp_ns(msg)) / 1e9)
