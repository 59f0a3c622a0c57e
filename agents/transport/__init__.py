"""The message layer under the agents: one envelope, one interface, two transports (Zenoh, in-memory).

Heavy imports stay lazy: importing this package does not import ``zenoh`` until a ``ZenohTransport``
is opened or a config is built.
"""
from __future__ import annotations

from agents.transport.base import Inbox, Transport
from agents.transport.config import ZenohOptions, build_config, free_port, loopback_endpoint
from agents.transport.envelope import (DEFAULT_MAX_SIZE, DROP_REASONS, PERFORMATIVES, BadMessage, Envelope,
                                       decode, new_message_id)
from agents.transport.local_transport import LocalBus, LocalTransport
from agents.transport.status import AgentStatus, quiescent
from agents.transport.trust import TrustPolicy
from agents.transport.zenoh_transport import ZenohTransport

__all__ = [
    "AgentStatus", "BadMessage", "DEFAULT_MAX_SIZE", "DROP_REASONS", "Envelope", "Inbox", "LocalBus",
    "LocalTransport", "PERFORMATIVES", "Transport", "TrustPolicy", "ZenohOptions", "ZenohTransport",
    "build_config", "decode", "free_port", "loopback_endpoint", "new_message_id", "quiescent",
]
