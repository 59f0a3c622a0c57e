"""An in-memory transport with the Zenoh transport's interface: a supported test double for the agent
layer, and the fastest choice when every agent of a MAS runs in one process.

Several ``LocalTransport`` objects on one ``LocalBus`` behave like processes on one network (each has
its own agents; presence, control and status are shared), so multi-process logic can be tested
without sockets. With ``wire=True`` every message between transports is encoded and decoded as on
the network (same checks, same drops).
"""
from __future__ import annotations

import threading
from typing import Any, Callable

from agents.transport.base import Transport
from agents.transport.envelope import DEFAULT_MAX_SIZE, Envelope
from agents.transport.status import AgentStatus


class LocalBus:
    """The shared 'network' of local transports: who is where, and fan-out of control/status."""

    def __init__(self) -> None:
        self.transports: list["LocalTransport"] = []
        self.lock = threading.RLock()

    def owner(self, mas: str, agent: str) -> "LocalTransport | None":
        with self.lock:
            for transport in self.transports:
                if transport.mas == mas and agent in transport._agents:
                    return transport
        return None

    def peers(self, mas: str) -> list["LocalTransport"]:
        with self.lock:
            return [t for t in self.transports if t.mas == mas]


class LocalTransport(Transport):
    """A ``Transport`` whose network is a ``LocalBus`` (a private one by default)."""

    def __init__(self, mas: str, bus: LocalBus | None = None, *, wire: bool = False,
                 max_message_size: int = DEFAULT_MAX_SIZE, identity: Any = None) -> None:
        super().__init__(mas, max_message_size=max_message_size, identity=identity)
        self.bus = bus or LocalBus()
        self.wire = wire
        self._statuses: dict[str, AgentStatus] = {}
        self._provided: set[tuple[str, str]] = set()                  # (agent, service) announced
        self._watches: dict[str, list[Callable[[str], None]]] = {}   # service -> callbacks

    def _open(self) -> None:
        with self.bus.lock:
            self.bus.transports.append(self)
            for peer in self.bus.peers(self.mas):
                for agent in peer._agents:
                    self._presence.update(agent, True)

    def _close(self) -> None:
        with self.bus.lock:
            self.bus.transports.remove(self)

    def _attach(self, agent: str) -> None:
        for peer in self.bus.peers(self.mas):
            peer._presence.update(agent, True)

    def _detach(self, agent: str) -> None:
        self._statuses.pop(agent, None)
        self._provided = {(a, s) for a, s in self._provided if a != agent}
        for peer in self.bus.peers(self.mas):
            peer._presence.update(agent, False)

    def _put(self, receiver: str, envelope: Envelope, encoded: Callable[[], bytes]) -> bool:
        owner = self.bus.owner(self.mas, receiver)
        if owner is None:
            return False
        if self.wire:
            where = f"local:{receiver}"
            self._send_payload(receiver, envelope, encoded(), lambda payload: owner.receive_bytes(receiver, payload, where))
        else:
            owner._deliver(receiver, envelope)
        return True

    def put_raw(self, receiver: str, payload: bytes) -> None:
        """Hand arbitrary bytes to ``receiver``'s inbox checks, as if they came from the network."""
        owner = self.bus.owner(self.mas, receiver)
        if owner is not None:
            owner.receive_bytes(receiver, payload, f"local:{receiver}")

    # -- directory facilitator: the peers' registrations are read directly (no queries, no tokens)
    def provide(self, agent: str, service: str) -> None:
        self._provided.add((agent, service))
        for peer in self.bus.peers(self.mas):
            if peer is not self:
                peer._announced(agent, service)

    def withdraw(self, agent: str, service: str) -> None:
        self._provided.discard((agent, service))

    def remote_registrations(self, timeout: float = 0.0) -> dict[str, list[str]]:
        found: dict[str, list[str]] = {}
        for peer in self.bus.peers(self.mas):
            if peer is not self:
                found.update(peer.local_registrations())
        return found

    def watch_registrations(self, service: str, callback: Callable[[str], None]) -> None:
        first = service not in self._watches
        self._watches.setdefault(service, []).append(callback)
        if first:
            for peer in self.bus.peers(self.mas):
                if peer is not self:
                    for agent, provided in sorted(peer._provided):
                        if provided == service and service in peer.local_registrations().get(agent, ()):
                            callback(agent)

    def _announced(self, agent: str, service: str) -> None:
        for callback in list(self._watches.get(service, ())):
            callback(agent)

    def _publish_control(self, message: dict[str, Any]) -> None:
        for peer in self.bus.peers(self.mas):
            peer._control_received(dict(message))

    def _publish_status(self, status: AgentStatus) -> None:
        self._statuses[status.agent] = status
        for peer in self.bus.peers(self.mas):
            peer._status_received(status)

    def collect_status(self, timeout: float = 1.0) -> list[AgentStatus]:
        statuses = []
        for peer in self.bus.peers(self.mas):
            for agent in peer._agents:
                statuses.append(peer._statuses.get(agent) or peer.status_of(agent, busy=False))
        return sorted(statuses, key=lambda s: s.agent)
