"""Who an agent believes: messages only from its own MAS, plans (``tellHow``) only from known agents.

The transport refuses every envelope whose ``mas`` is not ours (and key expressions are namespaced
by MAS, so other MAS traffic does not even reach us). Whether a ``tellHow`` (code!) is accepted is
decided by the agent layer with ``TrustPolicy.may_tell_how``: as in Jason, agents declared in the
same project file may send plans; any other sender (say, one that joined with ``faultmas agent run``)
only if the project allows it by name. Sender names are what the envelope says: on an open network
they are only as trustworthy as the links, so real deployments add TLS and access control
(docs/deployment.md).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Collection, Iterable

from agents.transport.envelope import Envelope

#: Performatives that carry plans (code) and therefore need ``may_tell_how``.
CODE_PERFORMATIVES = frozenset({"tellHow"})


@dataclass
class TrustPolicy:
    """The trust rules of one MAS; ``extra_check`` lets a project add its own rule."""

    mas: str
    declared_agents: frozenset[str] = frozenset()
    allowed_code_senders: frozenset[str] = frozenset()
    extra_check: Callable[[Envelope], bool] | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        self.declared_agents = frozenset(self.declared_agents)
        self.allowed_code_senders = frozenset(self.allowed_code_senders)

    def same_mas(self, envelope: Envelope) -> bool:
        return envelope.mas == self.mas

    def may_tell_how(self, sender: str) -> bool:
        """True if plans from ``sender`` are accepted (declared in the project, or allowed by name)."""
        return sender in self.declared_agents or sender in self.allowed_code_senders

    def refusal(self, envelope: Envelope) -> str | None:
        """Why ``envelope`` must be refused (a drop reason), or ``None`` to accept it."""
        if not self.same_mas(envelope):
            return "foreign_mas"
        if envelope.performative in CODE_PERFORMATIVES and not self.may_tell_how(envelope.sender):
            return "untrusted_code"
        if self.extra_check is not None and not self.extra_check(envelope):
            return "refused_by_policy"
        return None

    def allow(self, senders: Iterable[str]) -> None:
        """Allow more senders to send plans (e.g. from the project's configuration)."""
        self.allowed_code_senders = self.allowed_code_senders | frozenset(senders)


def is_member(name: str, members: Collection[str], creator_of: Callable[[str], "str | None"]) -> bool:
    """Is ``name`` an agent of the MAS: one of ``members`` (the project's), or made at run time by one
    (``creator_of``: who made it, as its process announces; a made agent may make more)? Names are claims in
    the default profile, so this keeps out only strangers that do not know a member's name."""
    seen = set()
    while name not in members:
        creator = creator_of(name)
        if creator is None or creator in seen:
            return False
        seen.add(name)
        name = creator
    return True
