"""Signed documents on keys that carry no envelope: the robots' percepts, actions, action results and clock,
and the inspector's minds and answers (the secure profile).

The same seal as an envelope's (``identity.Identity.seal``: ``seq`` and ``sig`` at the end of a JSON object),
checked the same way; only who must have signed is not read from the document but fixed by the key it came
on (a robot's percepts: the environment; a robot's actions: the agent that drives it, its namesake; an agent's
mind: that agent). What is refused is dropped through the transport's drop log (one line per reason per 10 s,
the rest summed up, every drop counted), never raised into the network thread that received it.
"""
from __future__ import annotations

from typing import Any, Callable

from agents.transport.envelope import BadMessage
from agents.transport.identity import ENVIRONMENT, Identity


class SealedChannel:
    """Seal and open documents for one process (its ``Identity``), dropping refused ones through ``drop``
    (``Transport._drop``: ``drop(reason, where, sender, detail)``)."""

    environment = ENVIRONMENT
    """The signer of what the robots send (percepts, action results, the clock)."""

    def __init__(self, identity: Identity, drop: Callable[[str, str, str | None, str], None]) -> None:
        self.identity = identity
        self._drop = drop

    def can_sign(self, signer: str) -> bool:
        return self.identity.can_sign(signer)

    def seal(self, signer: str, document: bytes) -> bytes:
        """``document`` (a JSON object) signed by ``signer``, one of this process's identities."""
        return self.identity.seal(signer, document)

    def open(self, payload: bytes, signer: str, where: str) -> bytes | None:
        """The document in ``payload`` as it was sealed, if ``signer`` sealed it and it is fresh (not seen on
        ``where`` before); else None, the drop logged and counted."""
        try:
            document, seq = self.identity.open(payload, lambda _document: signer)
            self.identity.check_fresh(signer, where, seq)
        except BadMessage as bad:
            self._drop(bad.reason, where, None if bad.reason == "unsigned" else bad.sender, bad.detail)
            return None
        return self.identity.as_sealed(document)

    def refuse(self, reason: str, where: str, sender: Any = None, detail: str = "") -> None:
        """Drop a message for another reason found by the caller (counted and logged like the others)."""
        self._drop(reason, where, sender if isinstance(sender, str) else None, detail)
