"""The directory facilitator (DF) behind ``.df_register``, ``.df_deregister``, ``.df_search`` and
``.df_subscribe``: which agents provide which services, and who wants to hear about new providers.

Semantics are those of Jason 3.3's local infrastructure (``jason.infra.local.BaseLocalMAS``), which a
Jason user's program runs on by default:

- a service is the text of the term (a string's own text, so ``"sell(book)"`` and ``sell(book)`` are
  one service); the optional type is accepted and **ignored** (``BaseRuntimeServices`` drops it), so a
  search with or without a type finds the same agents;
- ``register`` tells every subscriber of the service ``provider(Ag, "Service")`` (a ``tell`` from ``df``,
  the service as a string), each time it is called; ``subscribe`` tells the subscriber every current
  provider at once; deregistering tells nobody (Jason sends no ``untell``);
- an agent that is killed loses its registrations and subscriptions (``BaseLocalMAS.delAg``);
- ``search`` gives each provider once, in the order of Jason's ``HashSet`` of names (``jason_set_order``),
  not in registration order: an order that does not depend on who registered first is the only one two
  processes agree on, and it is the order Jason prints.

``Directory`` is the in-process back-end (one per ``LocalRuntime``); ``agents.directory.NetworkDirectory``
extends it to the agents of other processes of the MAS. The internal actions only see this interface.
"""
from __future__ import annotations

import threading
from typing import Callable, Iterable

from agentspeak.terms import to_str

TellProvider = Callable[[str, str, str], None]
"""``tell(subscriber, provider, service)``: deliver ``provider(Provider, "Service")`` from ``df``."""

DF_SENDER = "df"
"""The sender of the ``provider`` messages (Jason's DF is an agent named ``df``)."""


class Directory:
    """The services the agents of one process provide, and their subscriptions. Thread-safe: the
    network back-end reads it from transport threads."""

    def __init__(self, tell: TellProvider) -> None:
        self._tell = tell
        self._provides: dict[str, list[str]] = {}      # agent -> services (registration order)
        self._subscribers: dict[str, list[str]] = {}   # service -> subscribing agents
        self._lock = threading.RLock()

    # -- what the internal actions call ------------------------------------------------------------
    def register(self, agent: str, service: str) -> None:
        """``agent`` provides ``service``; its subscribers are told so (again, if already registered)."""
        with self._lock:
            services = self._provides.setdefault(agent, [])
            if service not in services:
                services.append(service)
            subscribers = list(self._subscribers.get(service, ()))
        for subscriber in subscribers:
            self._tell(subscriber, agent, service)

    def deregister(self, agent: str, service: str) -> None:
        """``agent`` no longer provides ``service`` (nobody is told)."""
        with self._lock:
            services = self._provides.get(agent)
            if services is not None and service in services:
                services.remove(service)
                if not services:
                    del self._provides[agent]

    def search(self, service: str) -> list[str]:
        """The agents providing ``service``, in Jason's order."""
        return jason_set_order(self.local_providers(service))

    def subscribe(self, agent: str, service: str) -> None:
        """Tell ``agent`` of every provider of ``service``, now and whenever one registers."""
        with self._lock:
            subscribers = self._subscribers.setdefault(service, [])
            if agent not in subscribers:
                subscribers.append(agent)
        for provider in self.providers_for_subscriber(agent, service):
            self._tell(agent, provider, service)

    def forget(self, agent: str) -> None:
        """``agent`` is gone (killed): its registrations and subscriptions go with it."""
        with self._lock:
            self._provides.pop(agent, None)
            for subscribers in self._subscribers.values():
                if agent in subscribers:
                    subscribers.remove(agent)

    # -- for back-ends -------------------------------------------------------------------------------
    def providers_for_subscriber(self, agent: str, service: str) -> list[str]:
        """The providers a new subscriber is told of, in Jason's order (a back-end adds those it reaches)."""
        return jason_set_order(self.local_providers(service))

    def local_providers(self, service: str) -> list[str]:
        with self._lock:
            return [agent for agent, services in self._provides.items() if service in services]

    def registrations(self) -> dict[str, list[str]]:
        """{agent: its services} for the agents of this process (a copy)."""
        with self._lock:
            return {agent: list(services) for agent, services in self._provides.items()}

    def subscribers_of(self, service: str) -> list[str]:
        with self._lock:
            return list(self._subscribers.get(service, ()))

    def tell(self, subscriber: str, provider: str, service: str) -> None:
        self._tell(subscriber, provider, service)


# -- Jason's order -------------------------------------------------------------------------------------
def java_string_hash(text: str) -> int:
    """Java's ``String.hashCode`` (over UTF-16 code units, 32-bit signed arithmetic)."""
    h = 0
    data = text.encode("utf-16-be")
    for i in range(0, len(data), 2):
        h = (31 * h + (data[i] << 8 | data[i + 1])) & 0xFFFFFFFF
    return h


def _java_capacity(size: int) -> int:
    """The table size of a ``java.util.HashSet`` after ``size`` additions (16, doubled past 3/4 full)."""
    capacity = 16
    while size > capacity * 3 // 4:
        capacity *= 2
    return capacity


def jason_set_order(names: Iterable[str]) -> list[str]:
    """``names`` without repeats, in the order Jason's ``dfSearch`` returns them: the iteration order of
    a ``HashSet<String>`` (by bucket ``(h ^ h>>>16) & (capacity-1)``). Names sharing a bucket keep their
    insertion order in Java, which two processes cannot agree on: here they are in alphabetical order."""
    unique = sorted(set(names))
    mask = _java_capacity(len(unique)) - 1

    def bucket(name: str) -> int:
        h = java_string_hash(name)
        return (h ^ (h >> 16)) & mask
    return sorted(unique, key=bucket)


def service_text(service: object) -> str:
    """Jason's ``df_register.getService``: a string's own text, any other term as it prints."""
    return service if isinstance(service, str) else to_str(service)
