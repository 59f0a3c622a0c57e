"""The directory facilitator (``.df_register``, ``.df_search``, ``.df_subscribe``...) across the processes
of a MAS: the in-process ``agentspeak.directory.Directory`` for this process's agents, plus what the
transport learns of the agents of the other processes. Same semantics as in one process (see there).

Design, and why:

- **Each process answers for its own agents** (a queryable on ``faultmas/<mas>/df/*``, answering with
  ``Directory.registrations``): the registrations live where the registering agent lives, so nothing has
  to be kept consistent between processes, and when a process dies (exit, kill, lost link) its
  queryable goes with its Zenoh session: a dead agent is never found again, with no clean-up protocol.
- **``.df_search`` is a query with a bounded timeout** (``registrations.QUERY_TIMEOUT``) to every process
  of the MAS: it returns as soon as all have answered (a few ms on loopback), and a hung process costs
  at most the timeout, never a hang. It is synchronous, as Jason's is: a registration made before a
  message was sent is found by the receiver's search.
- **Each registration is also a liveliness token** ``faultmas/<mas>/provides/<agent>/<service>``, which a
  process watches (with history) once one of its agents subscribes to the service: the token tells of
  providers registered before the subscription and after it, without a gap and without polling.
- **In the secure profile a registration cannot be forged**: a token carries no signature (anyone on the
  network can declare one), so it is only a hint; it is believed once the agent's own process confirms it
  with a document signed by the agent's key and bound to a fresh nonce of the asker's (no replay of an
  old answer). ``.df_search`` reads only such documents. A forged or unconfirmed announcement is
  logged and ignored. In the default profile sender names are claims, as for every message.
"""
from __future__ import annotations

from functools import partial

from agents.transport.base import Transport
from agentspeak.directory import Directory, TellProvider, jason_set_order


class NetworkDirectory(Directory):
    """The ``Directory`` of one process of a MAS whose other agents run elsewhere (see the module)."""

    def __init__(self, tell: TellProvider, transport: Transport) -> None:
        super().__init__(tell)
        self.transport = transport
        self._remote: dict[str, set[str]] = {}   # service -> providers in other processes heard of so far
        transport.registrations = self.registrations

    def register(self, agent: str, service: str) -> None:
        super().register(agent, service)
        self.transport.provide(agent, service)

    def deregister(self, agent: str, service: str) -> None:
        super().deregister(agent, service)
        self.transport.withdraw(agent, service)

    def search(self, service: str) -> list[str]:
        providers = self.local_providers(service)
        for agent, services in self.transport.remote_registrations().items():
            if service in services:
                providers.append(agent)
        return jason_set_order(providers)

    def subscribe(self, agent: str, service: str) -> None:
        super().subscribe(agent, service)  # this process's providers, told at once
        with self._lock:
            known = self._remote.get(service)
            if known is None:
                self._remote[service] = set()
            else:
                known = sorted(known)
        if known is None:  # the first subscriber here: the watch reports the providers so far, then new ones
            self.transport.watch_registrations(service, partial(self._remote_provider, service))
        else:
            for provider in known:
                self.tell(agent, provider, service)

    def forget(self, agent: str) -> None:
        services = self.registrations().get(agent, ())
        super().forget(agent)
        for service in services:
            self.transport.withdraw(agent, service)

    def _remote_provider(self, service: str, provider: str) -> None:
        """A provider of ``service`` in another process (checked by the transport): tell the subscribers."""
        with self._lock:
            self._remote.setdefault(service, set()).add(provider)
        for subscriber in self.subscribers_of(service):
            self.tell(subscriber, provider, service)
