"""Agent status (idle/busy and message counters) so a launcher can tell, across processes, that every
agent is idle and no message is in flight.

Each agent's transport counts the messages it *sent* (one per reachable receiver) and *received*
(delivered valid messages). The MAS is quiescent when every agent is idle and the sums are equal.
One snapshot can be taken while a message is between a send and a receive that were read at
different moments, so a launcher should stop only after two consecutive snapshots that are both
quiescent and have the same totals (the classic four-counter rule).
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from typing import Iterable

from agents.transport.envelope import is_valid_name


@dataclass(frozen=True)
class AgentStatus:
    """One agent's state as published on ``faultmas/<mas>/status/<agent>``."""

    agent: str
    busy: bool
    sent: int
    received: int

    def encode(self) -> bytes:
        return json.dumps(asdict(self), separators=(",", ":")).encode()

    @classmethod
    def decode(cls, payload: bytes) -> "AgentStatus":
        """Parse a status; ``ValueError`` if it is not one."""
        data = json.loads(payload)
        if (not isinstance(data, dict) or not is_valid_name(data.get("agent"))
                or not isinstance(data.get("busy"), bool)
                or not all(type(data.get(k)) is int for k in ("sent", "received"))):
            raise ValueError(f"not an agent status: {payload[:80]!r}")
        return cls(data["agent"], data["busy"], data["sent"], data["received"])


def totals(statuses: Iterable[AgentStatus]) -> tuple[int, int]:
    """(sent, received) summed over ``statuses``."""
    sent = received = 0
    for status in statuses:
        sent += status.sent
        received += status.received
    return sent, received


def quiescent(statuses: Iterable[AgentStatus]) -> bool:
    """Every agent idle and as many messages received as sent (see the module note on two snapshots)."""
    statuses = list(statuses)
    sent, received = totals(statuses)
    return all(not s.busy for s in statuses) and sent == received
