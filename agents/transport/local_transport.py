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
from agents.transport.name_claims import Claimant
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
        self._subscribed: set[tuple[str, str]] = set()                        # (agent, service) announced
        self._subscription_callbacks: list[Callable[[str, str, bool], None]] = []

    def _open(self) -> None:
        with self.bus.lock:
            self.bus.transports.append(self)
            for peer in self.bus.peers(self.mas):
                for agent in peer._agents:
                    self._presence.update(agent, True)
                self._creators.update(peer._creators)

    def _close(self) -> None:
        with self.bus.lock:
            self.bus.transports.remove(self)

    def _attach(self, agent: str) -> None:
        creator = self._creators.get(agent)
        for peer in self.bus.peers(self.mas):
            if creator is not None:
                peer._created(agent, creator)
            peer._presence.update(agent, True)

    def _detach(self, agent: str) -> None:
        self._statuses.pop(agent, None)
        for subscriber, service in [k for k in self._subscribed if k[0] == agent]:
            self.withdraw_subscription(subscriber, service)
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

    def _ask_claims(self, name: str, timeout: float) -> dict[Claimant, bool]:
        """Every transport on the bus answers at once, from its own claims (as a process does over Zenoh)."""
        return {claimant: won for peer in self.bus.peers(self.mas)
                for held, claimant, won in peer._name_claims.held() if held == name}

    def put_raw(self, receiver: str, payload: bytes) -> None:
        """Hand arbitrary bytes to ``receiver``'s inbox checks, as if they came from the network."""
        owner = self.bus.owner(self.mas, receiver)
        if owner is not None:
            owner.receive_bytes(receiver, payload, f"local:{receiver}")

    # -- directory facilitator: the peers' registrations and subscriptions are read directly
    def remote_registrations(self, timeout: float = 0.0,
                             subscribe: tuple[str, str] | None = None) -> dict[str, list[str]]:
        found: dict[str, list[str]] = {}
        for peer in self.bus.peers(self.mas):
            if peer is not self:
                found.update(peer.local_registrations(subscribe))
        return found

    def announce_subscription(self, agent: str, service: str) -> None:
        if (agent, service) not in self._subscribed:
            self._subscribed.add((agent, service))
            self._tell_peers(agent, service, True)

    def withdraw_subscription(self, agent: str, service: str) -> None:
        if (agent, service) in self._subscribed:
            self._subscribed.discard((agent, service))
            self._tell_peers(agent, service, False)

    def on_subscription(self, callback: Callable[[str, str, bool], None]) -> None:
        self._subscription_callbacks.append(callback)
        for peer in self.bus.peers(self.mas):
            if peer is not self:
                for agent, service in sorted(peer._subscribed):
                    callback(agent, service, True)

    def _tell_peers(self, agent: str, service: str, present: bool) -> None:
        for peer in self.bus.peers(self.mas):
            if peer is not self:
                for callback in list(peer._subscription_callbacks):
                    callback(agent, service, present)

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
