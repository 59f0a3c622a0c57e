"""The directory facilitator (``.df_register``, ``.df_search``, ``.df_subscribe``...) across the processes
of a MAS: the in-process ``agentspeak.directory.Directory`` for this process's agents, plus the agents
of the other processes. Same semantics as in one process (see there), message order included.

Design, and why:

- **Each process answers for its own agents** (a queryable on ``faultmas/<mas>/df/*`` answering with
  ``Directory.registrations``): a registration lives where its agent lives, so nothing has to be kept
  consistent between processes, and when a process dies (exit, kill, lost link) its queryable goes with
  its Zenoh session: a dead agent is never found again, with no clean-up protocol.
- **``.df_search`` is a query with a bounded timeout** (``registrations.QUERY_TIMEOUT``) to every process
  of the MAS: it returns as soon as all have answered (a few ms on loopback); a hung process costs at
  most the timeout, never a hang. It is synchronous, as Jason's is: a registration made before a message
  was sent is found by the receiver's search.
- **``.df_subscribe`` is the same query, saying who subscribes to what**: each process that answers
  remembers the subscriber in one step with its answer, so once ``.df_subscribe`` returns every live
  process knows it, and the subscriber is told of the current providers (those of the answers) before
  it goes on, as Jason's ``dfSubscribe`` tells them. Then a **liveliness token**
  ``faultmas/<mas>/subscribes/<agent>/<service>`` stands for the subscription: processes that start later
  see it (with history) and tell the subscriber of their providers; when the subscriber's process dies,
  it goes.
- **A registration tells each known subscriber at once, with a speech act from the provider itself**
  (``re`` = ``PROVIDER_NOTICE``) on the agents' own message path: it is ordered with what the provider
  sends next, as Jason's DF puts it in the subscriber's mailbox before the provider goes on. The
  receiving process checks it (``provider(<its sender>, "S")``, to an agent subscribed to S) and delivers
  it as Jason does, from ``df``. A registration and a subscriber's arrival are handled one at a time, so
  each provider is told to each subscriber once.
- **In the secure profile nothing can be forged**: a notice is an envelope signed by the provider (so only
  an agent can announce itself), and a search reads only answers signed by the registering agent and
  bound to a fresh nonce of the asker's (an outsider cannot answer for an agent, nor replay an old
  answer). A query or token naming a subscriber that did not subscribe makes providers tell that agent,
  whose process refuses the notices (``not_subscribed``); an outsider learns nothing a query would not
  tell it.
"""
from __future__ import annotations

import threading
from typing import Callable

from agents.transport.base import Transport
from agentspeak.communication import Message
from agentspeak.directory import Directory, TellProvider, jason_set_order
from agentspeak.terms import Literal

PROVIDER_NOTICE = "df"
"""The ``re`` of a provider's notice to a subscriber in another process (message ids are never this)."""


def provider_notice(provider: str, subscriber: str, service: str) -> Message:
    return Message(provider, subscriber, "tell", Literal("provider", (Literal(provider), service)),
                   in_reply_to=PROVIDER_NOTICE)


def notice_service(sender: str, content: object) -> str | None:
    """The service of a well-formed notice from ``sender`` (``provider(<sender>, "S")``), else None."""
    if type(content) is Literal and content.functor == "provider" and len(content.args) == 2 and not content.neg:
        who, service = content.args
        if type(who) is Literal and who.functor == sender and not who.args and isinstance(service, str):
            return service
    return None


class NetworkDirectory(Directory):
    """The ``Directory`` of one process of a MAS whose other agents run elsewhere (see the module).
    ``send``: the agents' message path (``LocalRuntime.route``)."""

    def __init__(self, tell: TellProvider, transport: Transport, send: Callable[[Message], None]) -> None:
        super().__init__(tell)
        self.transport = transport
        self._send = send
        self._remote_subscribers: dict[str, list[str]] = {}  # service -> subscribers in other processes
        self._notices = threading.Lock()  # a registration and a subscriber's arrival: one at a time
        transport.registrations = self._answer
        transport.on_subscription(self._on_remote_subscription)

    def register(self, agent: str, service: str) -> None:
        with self._notices:  # who is told is decided here; the messages go out after (no lock held on a send)
            super().register(agent, service)
            subscribers = list(self._remote_subscribers.get(service, ()))
        for subscriber in subscribers:
            self._send(provider_notice(agent, subscriber, service))

    def search(self, service: str) -> list[str]:
        return self._providers(service, self.transport.remote_registrations())

    def subscribe(self, agent: str, service: str) -> None:
        super().subscribe(agent, service)  # the providers of every process, told now
        self.transport.announce_subscription(agent, service)  # for processes that come later

    def providers_for_subscriber(self, agent: str, service: str) -> list[str]:
        return self._providers(service, self.transport.remote_registrations(subscribe=(agent, service)))

    def forget(self, agent: str) -> None:
        with self._lock:
            services = [service for service, subscribers in self._subscribers.items() if agent in subscribers]
        super().forget(agent)
        for service in services:
            self.transport.withdraw_subscription(agent, service)

    def _providers(self, service: str, remote: dict[str, list[str]]) -> list[str]:
        providers = self.local_providers(service)
        providers += [agent for agent, services in remote.items() if service in services]
        return jason_set_order(providers)

    def _answer(self, subscribed: tuple[str, str] | None) -> dict[str, list[str]]:
        """What this process answers a directory query with (on a Zenoh thread): its registrations, and
        the asker remembered as a subscriber in the same step (a registration after it tells it)."""
        with self._notices:
            if subscribed is not None:
                subscriber, service = subscribed
                subscribers = self._remote_subscribers.setdefault(service, [])
                if subscriber not in subscribers:
                    subscribers.append(subscriber)
            return self.registrations()

    def _on_remote_subscription(self, subscriber: str, service: str, present: bool) -> None:
        """A subscription token came or went: a subscriber this process did not hear of by its query
        (this process started later) is told of the providers here."""
        with self._notices:
            subscribers = self._remote_subscribers.setdefault(service, [])
            if not present:
                if subscriber in subscribers:
                    subscribers.remove(subscriber)
                return
            if subscriber in subscribers:
                return  # it asked us when it subscribed: told already
            subscribers.append(subscriber)
            providers = jason_set_order(self.local_providers(service))  # Jason's dfSubscribe: all current
        for provider in providers:
            self._send(provider_notice(provider, subscriber, service))
