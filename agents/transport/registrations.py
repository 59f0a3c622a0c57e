"""The directory facilitator on the wire: one agent's registrations as a document bound to one query.

A process answers a query for ``keys.df_key(mas, agent)`` with, per agent of its own that has
registrations::

    {"mas":"cnp","agent":"bob","services":["bidder"],"nonce":"<the asker's nonce>"}

In the secure profile the document is sealed by the agent (``identity.seal``: ``seq`` and ``sig`` at its
end), so a receiver checks that the agent it names signed it, and the nonce it chose for this query
proves the answer is not a replay of an older one (a registration since withdrawn, or of an agent since
dead). In the default profile the document is plain JSON and, like every sender name there, a claim.
"""
from __future__ import annotations

import json
import secrets
from typing import Any, Sequence

from agents.transport.envelope import BadMessage, is_valid_name

QUERY_TIMEOUT = 2.0
"""Seconds a directory query waits for the processes of the MAS; it ends as soon as all have answered
(on loopback a few ms), so this bounds only a hung process (``.df_search`` never hangs)."""

#: Why the directory facilitator's traffic is refused (counted and logged as drops, like envelopes): an
#: answer that is no registration document or answers another query, a query or subscription token that
#: cannot be read, a provider's notice that is not about its sender or goes to an agent that did not
#: subscribe (``agents.zenoh_arch``); in the secure profile also ``identity.IDENTITY_DROP_REASONS``.
DF_DROP_REASONS = ("bad_registration", "replayed", "bad_df_query", "bad_subscription", "bad_df_notice",
                   "not_subscribed")


def new_nonce() -> str:
    return secrets.token_hex(12)


def encode_services(mas: str, agent: str, services: Sequence[str], nonce: str, identity: Any = None) -> bytes:
    """The document answering query ``nonce`` for ``agent`` (sealed by ``agent`` when ``identity`` can)."""
    document = json.dumps({"mas": mas, "agent": agent, "services": list(services), "nonce": nonce},
                          separators=(",", ":")).encode()
    if identity is not None and identity.can_sign(agent):
        return identity.seal(agent, document)
    return document


def open_services(payload: bytes, mas: str, nonce: str, identity: Any = None,
                  max_size: int = 256 * 1024) -> tuple[str, list[str]]:
    """(agent, services) from an answer to query ``nonce``; ``BadMessage`` when it must be refused."""
    if len(payload) > max_size:
        raise BadMessage("too_large", f"{len(payload)} bytes > limit {max_size}")
    parsed: list[dict] = []

    def agent_of(document: bytes) -> Any:
        try:
            data = json.loads(document)
        except (ValueError, RecursionError) as exc:
            raise BadMessage("not_json", str(exc)[:80]) from None
        if not isinstance(data, dict):
            raise BadMessage("bad_registration", "expected a JSON object")
        parsed.append(data)
        return data.get("agent")

    if identity is None:
        agent_of(payload)
    else:
        identity.open(payload, agent_of)  # signed by the agent it names (BadMessage otherwise)
    data = parsed[-1]
    agent, services = data.get("agent"), data.get("services")
    if data.get("mas") != mas or not is_valid_name(agent) or not isinstance(services, list) \
            or not all(isinstance(s, str) for s in services):
        raise BadMessage("bad_registration", "expected mas, agent and a list of service strings",
                         agent if isinstance(agent, str) else None)
    if data.get("nonce") != nonce:
        raise BadMessage("replayed", "an answer to another directory query", agent)
    return agent, services
