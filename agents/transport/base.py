"""What every transport does the same way: local registration, checks and drops, counters, presence.

A concrete transport (Zenoh, in-memory) only moves bytes and presence events; this base decides what
is accepted. Callbacks from the network run on foreign threads, so everything handed to the agent
layer goes through ``on_envelope`` callbacks that must not block (``Inbox`` is the standard one).
"""
from __future__ import annotations

import collections
import logging
import threading
import time
from abc import ABC, abstractmethod
from collections import Counter
from contextlib import contextmanager
from threading import get_ident
from typing import TYPE_CHECKING, Any, Callable, Iterable, Iterator, Mapping, Sequence

from agents.transport.envelope import (BATCH_BYTES, BATCH_SEPARATOR, DEFAULT_MAX_SIZE, QUESTIONS, BadMessage,
                                       Envelope, decode, split_batch)
from agents.transport.drop_log import DropLog
from agents.transport.keys import check_name
from agents.transport.name_claims import CLAIM_TIMEOUT, Claimant, NameClaims
from agents.transport.outbox import Outbox
from agents.transport.registrations import QUERY_TIMEOUT
from agents.transport.status import AgentStatus

if TYPE_CHECKING:
    from agents.transport.identity import Identity
    from agents.transport.sealed import SealedChannel

log = logging.getLogger("faultmas.transport")

OnEnvelope = Callable[[Envelope], None]
OnDelivered = Callable[[], None]
OnPresence = Callable[[str, bool], None]
OnControl = Callable[[dict[str, Any]], None]
OnStatus = Callable[[AgentStatus], None]


class Inbox:
    """A thread-safe mailbox: the network thread appends, the agent's thread takes; ``wake`` is called
    after each append (e.g. to set the event the agent's reasoning loop sleeps on).

    Appending never blocks and costs no lock while the reader is busy (a deque, and an event set
    only when the reader may be asleep), so a burst of messages does not bounce the GIL per message.
    """

    def __init__(self, wake: Callable[[], None] | None = None) -> None:
        self._items: collections.deque[Envelope] = collections.deque()
        self._ready = threading.Event()
        self._wake = wake

    def __call__(self, envelope: Envelope) -> None:
        self._items.append(envelope)
        if not self._ready.is_set():
            self._ready.set()
        if self._wake is not None:
            self._wake()

    def get(self, timeout: float | None = None) -> Envelope | None:
        """The next envelope, waiting up to ``timeout`` seconds (``None`` when none came)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            try:
                return self._items.popleft()
            except IndexError:
                pass
            self._ready.clear()
            if self._items:  # appended between popleft and clear: its set() may have been skipped
                continue
            remaining = None if deadline is None else deadline - time.monotonic()
            if remaining is not None and remaining <= 0:
                return None
            self._ready.wait(remaining)

    def drain(self) -> list[Envelope]:
        """Every envelope waiting now, oldest first, without blocking."""
        items = []
        try:
            while True:
                items.append(self._items.popleft())
        except IndexError:
            return items

    def __len__(self) -> int:
        return len(self._items)


class Presence:
    """The set of live agents, fed by join/leave events that may repeat; reports each change once."""

    def __init__(self) -> None:
        self._alive: set[str] = set()
        self._departed: set[str] = set()     # seen alive, then gone (killed, ended, died) and not back
        self._callbacks: list[OnPresence] = []
        self._changed = threading.Condition()

    def update(self, agent: str, alive: bool) -> None:
        with self._changed:
            if (agent in self._alive) == alive:
                return  # a join seen twice (token + history) is reported once
            (self._alive.add if alive else self._alive.discard)(agent)
            (self._departed.discard if alive else self._departed.add)(agent)
            callbacks = list(self._callbacks)
            self._changed.notify_all()
        for callback in callbacks:
            _call_safely(callback, agent, alive)

    def subscribe(self, callback: OnPresence) -> None:
        """Call ``callback(agent, alive)`` on every change, first once per agent alive now."""
        with self._changed:
            self._callbacks.append(callback)
            now = sorted(self._alive)
        for agent in now:
            _call_safely(callback, agent, True)

    def is_alive(self, agent: str) -> bool:
        return agent in self._alive  # one set lookup: atomic under the GIL, no lock on the send path

    def alive(self) -> frozenset[str]:
        with self._changed:
            return frozenset(self._alive)

    def departed(self) -> frozenset[str]:
        """Agents seen alive that are gone now."""
        with self._changed:
            return frozenset(self._departed)

    def wait_for(self, agents: Iterable[str], timeout: float, alive: bool = True) -> bool:
        """Block until every agent in ``agents`` is alive (or, with ``alive=False``, gone)."""
        wanted = set(agents)
        with self._changed:
            return self._changed.wait_for(
                lambda: wanted <= self._alive if alive else not (wanted & self._alive), timeout)


class _Encoded:
    """The wire bytes of one envelope, computed on first use (a broadcast encodes once); signed by its
    sender in the secure profile (``identity``)."""

    __slots__ = ("envelope", "payload", "identity")

    def __init__(self, envelope: Envelope, identity: "Identity | None" = None) -> None:
        self.envelope = envelope
        self.payload: bytes | None = None
        self.identity = identity

    def __call__(self) -> bytes:
        if self.payload is None:
            self.payload = self.envelope.encode()
            if self.identity is not None:
                self.payload = self.identity.seal(self.envelope.sender, self.payload)
        return self.payload


def _call_safely(callback: Callable[..., Any], *args: Any) -> None:
    try:
        callback(*args)
    except Exception:  # a broken callback must not kill a network thread
        log.exception("callback %r failed", callback)


class Transport(ABC):
    """The interface the agent runtime uses; see ``ZenohTransport`` and ``LocalTransport``.

    ``send`` counts one *sent* message per reachable receiver, delivery counts one *received*;
    ``dropped`` counts refused messages by reason (see ``envelope.DROP_REASONS``).
    """

    def __init__(self, mas: str, *, max_message_size: int = DEFAULT_MAX_SIZE,
                 identity: "Identity | None" = None) -> None:
        self.mas = check_name(mas, "MAS name")
        self.max_message_size = max_message_size
        self.identity = identity
        """The secure profile (``identity.Identity``): what goes out is signed, what comes in must be
        signed by a member's key and fresh. None: the default profile (names are claims)."""
        self.dropped: Counter[str] = Counter()
        self._drop_log = DropLog(log)
        self.sent: Counter[str] = Counter()       # by sender
        self.received: Counter[str] = Counter()   # by receiver
        self._counters = threading.Lock()
        self._agents: dict[str, OnEnvelope] = {}
        self._delivered: dict[str, OnDelivered] = {}
        self._creators: dict[str, str] = {}  # agent made at run time (here or elsewhere) -> who made it
        self._name_claims = NameClaims()     # names this process claims for agents made at run time
        self._outbox = Outbox()
        self._batching: int | None = None  # the thread whose sends to other processes are batched
        self._presence = Presence()
        self._control_callbacks: list[OnControl] = []
        self._status_callbacks: list[OnStatus] = []
        self.registrations: Callable[[tuple[str, str] | None], Mapping[str, Sequence[str]]] | None = None
        """The directory facilitator's registrations of this process's agents, {agent: services}: what
        this process answers directory queries with (set by ``agents.directory.NetworkDirectory``). Called
        with (subscriber, service) when the query comes from an agent that subscribes to the service."""
        self._opened = False

    # -- life cycle ---------------------------------------------------------------------------
    def open(self) -> "Transport":
        if not self._opened:
            self._open()
            self._opened = True
        return self

    def close(self) -> None:
        if self._opened:
            self._outbox.close()
            for agent in list(self._agents):
                self.unregister(agent)
            self._close()
            self._opened = False
            self._drop_log.flush()

    def __enter__(self) -> "Transport":
        return self.open()

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- agents ----------------------------------------------------------------------------------
    def register(self, agent: str, on_envelope: OnEnvelope, on_delivered: OnDelivered | None = None, *,
                 creator: str | None = None) -> None:
        """Receive ``agent``'s messages through ``on_envelope`` (must not block) and announce it alive.
        ``on_delivered``: called after each group of messages handed over together (one network
        message, which may be a batch), e.g. to wake the agent once per group, not per message.
        ``creator``: the agent that made it at run time (``.create_agent``), announced with it (``creator_of``)."""
        check_name(agent)
        if creator is not None:
            check_name(creator)
        if not self._opened:
            raise RuntimeError("open the transport before registering agents")
        if agent in self._agents:
            raise ValueError(f"agent {agent!r} is already registered in this process")
        if creator is not None:
            self._creators[agent] = creator
        else:  # a name another process's made agent once had: this agent is not made
            self._creators.pop(agent, None)
        self._agents[agent] = on_envelope
        if on_delivered is not None:
            self._delivered[agent] = on_delivered
        self._attach(agent)

    def unregister(self, agent: str) -> None:
        """Stop receiving for ``agent`` and withdraw its presence."""
        self._outbox.flush()  # what it sent goes before its presence does
        if self._agents.pop(agent, None) is not None:
            self._delivered.pop(agent, None)
            self._detach(agent)
        self.release_name(agent)

    def local_agents(self) -> tuple[str, ...]:
        return tuple(self._agents)

    def creator_of(self, agent: str) -> str | None:
        """Who made ``agent`` at run time, in any process of the MAS (None: not made so). Remembered after the
        agent is gone: what it sent last (a ``.stopMAS``, an ``achieve``) may arrive after its presence went, and
        is still from a member. A claim in the default profile, as every name is (``trust.is_member``); in the
        secure profile none (a token proves nothing there, and no agent is made at run time)."""
        return self._creators.get(agent) if self.identity is None else None

    def claim_name(self, name: str, creator: str, timeout: float = CLAIM_TIMEOUT) -> bool:
        """Claim ``name`` for an agent ``creator`` makes at run time, deciding with the other processes of the MAS
        (``name_claims``): True when this process may register an agent under it (the claim is held until that agent
        unregisters, or ``release_name``), False when another process has it or gets it (the creator takes the next
        name). ``NameUndecided`` when not every process answered within ``timeout`` seconds."""
        check_name(name)
        return self._name_claims.claim(name, check_name(creator), self._ask_claims, timeout)

    def release_name(self, name: str) -> None:
        """Withdraw this process's claim on ``name`` (the agent it was for is gone, or was never made)."""
        self._name_claims.release(name)

    def _created(self, agent: str, creator: str) -> None:
        """For concrete transports: another process announced an agent made at run time by ``creator``."""
        self._creators[agent] = creator

    # -- messages --------------------------------------------------------------------------------
    def send(self, envelope: Envelope) -> tuple[str, ...]:
        """Send ``envelope`` to each of its receivers; return the receivers nobody listens for."""
        if envelope.mas != self.mas:
            raise ValueError(f"envelope for MAS {envelope.mas!r} sent on the transport of MAS {self.mas!r}")
        unreachable = []
        encoded = _Encoded(envelope, self.identity)
        local = self._agents
        for receiver in envelope.receivers:
            if receiver in local:  # served without the network (FIFO per pair holds: always this path)
                reached = self._deliver(receiver, envelope)
            else:
                reached = self._put(receiver, envelope, encoded)
            if not reached:
                unreachable.append(receiver)
        if len(unreachable) < len(envelope.receivers):
            with self._counters:
                self.sent[envelope.sender] += len(envelope.receivers) - len(unreachable)
        return tuple(unreachable)

    @contextmanager
    def batching(self) -> Iterator[None]:
        """While in this block, what the calling thread sends to other processes is held and put in
        batches (see ``outbox``): for the thread that runs the agents, which calls ``flush`` when
        they go idle. Other threads' messages still go out at once."""
        if self._batching is not None:  # another loop batches already: this one sends at once
            yield
            return
        self._batching = get_ident()
        try:
            yield
        finally:
            self._batching = None
            self._outbox.flush()

    def flush(self) -> None:
        """Send every message held for a batch now."""
        self._outbox.flush()

    def _send_payload(self, receiver: str, envelope: Envelope, payload: bytes,
                      put: Callable[[bytes], None]) -> None:
        """For concrete transports: ``put(payload)`` now, or hold it when the caller batches. Questions
        and answers are not held (someone waits for them; the runtime need not go idle meanwhile)."""
        if self._batching is not None and get_ident() == self._batching:
            self._outbox.hold(receiver, payload, put, envelope.in_reply_to is not None
                              or envelope.performative in QUESTIONS)
        else:
            put(payload)

    def receive_bytes(self, agent: str, payload: bytes, where: str = "") -> None:
        """Check bytes that arrived for ``agent`` (one message or a batch) and deliver each message,
        or drop it with one log line; then ``on_delivered`` once."""
        if BATCH_SEPARATOR not in payload:
            if self._receive(agent, payload, where):
                self._count_received(agent, 1)
                self._group_delivered(agent)
            return
        limit = max(self.max_message_size, BATCH_BYTES)
        if len(payload) > limit:
            self._drop("too_large", where or agent, None, f"{len(payload)} bytes > limit {limit}")
            return
        delivered = 0
        try:
            for message in split_batch(payload):
                try:
                    delivered += self._receive(agent, message, where)
                except Exception:  # the rest of the batch is not lost over one message
                    log.exception("a message for %s could not be handled", agent)
        finally:
            if delivered:
                self._count_received(agent, delivered)
                self._group_delivered(agent)

    def _receive(self, agent: str, payload: bytes, where: str) -> bool:
        """Decode and check one message and hand it to ``agent``'s callback; False if refused."""
        try:
            if self.identity is None:
                envelope = decode(payload, self.max_message_size)
            else:
                envelope = self._open_signed(agent, payload)
        except BadMessage as bad:
            self._drop(bad.reason, where or agent, bad.sender, bad.detail)
            return False
        if envelope.mas != self.mas:
            self._drop("foreign_mas", where or agent, envelope.sender, f"MAS {envelope.mas!r}")
        elif agent not in envelope.receivers:
            self._drop("not_addressed", where or agent, envelope.sender, f"to {list(envelope.receivers)}")
        else:
            return self._hand_over(agent, envelope)
        return False

    def _open_signed(self, agent: str, payload: bytes) -> Envelope:
        """The secure profile's check: signed by the key of the sender it names, never seen before."""
        if len(payload) > self.max_message_size:
            raise BadMessage("too_large", f"{len(payload)} bytes > limit {self.max_message_size}")
        decoded: list[Envelope] = []

        def sender_of(document: bytes) -> str:
            decoded.append(decode(document, self.max_message_size))
            return decoded[-1].sender

        _, seq = self.identity.open(payload, sender_of)
        envelope = decoded[-1]
        if envelope.mas == self.mas and agent in envelope.receivers:  # else dropped as before, not remembered
            self.identity.check_fresh(envelope.sender, agent, seq)
        return envelope

    def _deliver(self, agent: str, envelope: Envelope) -> bool:
        """Deliver one envelope to a local agent (a group of one)."""
        if not self._hand_over(agent, envelope):
            return False
        self._count_received(agent, 1)
        self._group_delivered(agent)
        return True

    def _hand_over(self, agent: str, envelope: Envelope) -> bool:
        callback = self._agents.get(agent)
        if callback is None:
            return False
        try:
            callback(envelope)
        except Exception:  # the agent's problem; the network thread carries on
            log.exception("delivery to agent %s failed", agent)
        return True

    def _count_received(self, agent: str, count: int) -> None:
        with self._counters:
            self.received[agent] += count

    def _group_delivered(self, agent: str) -> None:
        callback = self._delivered.get(agent)
        if callback is not None:
            _call_safely(callback)

    def report_drop(self, envelope: Envelope, receiver: str, reason: str, detail: str = "") -> None:
        """For the agent layer: refuse a delivered envelope (e.g. ``unparsable_content``,
        ``untrusted_code``) with the same single log line and the same ``dropped`` counter."""
        self._drop(reason, f"agent {receiver}", envelope.sender, detail)

    def sealed_channel(self) -> "SealedChannel | None":
        """In the secure profile, what seals and checks this process's documents on keys that carry no envelope
        (robots' percepts and actions, the inspector's answers), drops counted and logged as this transport's;
        None in the default profile."""
        if self.identity is None:
            return None
        from agents.transport.sealed import SealedChannel
        return SealedChannel(self.identity, self._drop)

    def report_refused(self, reason: str, where: str, sender: str | None = None, detail: str = "") -> None:
        """For other layers: a message refused on ``where`` (a key), counted and logged like every drop."""
        self._drop(reason, where, sender if isinstance(sender, str) else None, detail)

    def report_control_refused(self, message: dict, reason: str) -> None:
        """For the agent layer: a control message (e.g. ``stop``) refused, logged and counted as a drop."""
        by = message.get("by")
        self._drop(reason, "the control key", by if isinstance(by, str) else None,
                   f"command {str(message.get('command'))[:30]!r}")

    def _drop(self, reason: str, where: str, sender: str | None, detail: str = "") -> None:
        with self._counters:
            self.dropped[reason] += 1
        self._drop_log.drop(reason, where, sender, detail)  # rate-limited per reason, summed up, never silent

    # -- presence --------------------------------------------------------------------------------
    def on_presence(self, callback: OnPresence) -> None:
        """``callback(agent, alive)`` on each join/leave in this MAS (reported once each); agents
        already alive are reported at once."""
        self._presence.subscribe(callback)

    def alive_agents(self) -> frozenset[str]:
        return self._presence.alive()

    def departed_agents(self) -> frozenset[str]:
        """Agents of this MAS seen alive that have left since (killed, ended or died) and not come back."""
        return self._presence.departed()

    def wait_for_agents(self, agents: Iterable[str], timeout: float = 10.0, alive: bool = True) -> bool:
        """Wait until all ``agents`` are alive (or all gone with ``alive=False``); False on timeout."""
        return self._presence.wait_for(agents, timeout, alive)

    # -- control and status ----------------------------------------------------------------------
    def publish_control(self, command: str, **fields: Any) -> None:
        """Send a MAS-wide command (e.g. ``stop``) to every process of the MAS, this one included."""
        self._outbox.flush()  # messages sent before a stop arrive before it
        self._publish_control({"command": command, **fields})

    def on_control(self, callback: OnControl) -> None:
        self._control_callbacks.append(callback)

    def status_of(self, agent: str, busy: bool) -> AgentStatus:
        with self._counters:
            return AgentStatus(agent, busy, self.sent[agent], self.received[agent])

    def publish_status(self, agent: str, busy: bool) -> AgentStatus:
        """Publish ``agent``'s idle/busy state with its counters; also kept for status queries."""
        self._outbox.flush()  # 'idle' only once what was sent is on its way
        status = self.status_of(agent, busy)
        self._publish_status(status)
        return status

    def on_status(self, callback: OnStatus) -> None:
        self._status_callbacks.append(callback)

    def _control_received(self, message: dict[str, Any]) -> None:
        for callback in list(self._control_callbacks):
            _call_safely(callback, message)

    def _status_received(self, status: AgentStatus) -> None:
        for callback in list(self._status_callbacks):
            _call_safely(callback, status)

    @abstractmethod
    def collect_status(self, timeout: float = 1.0) -> list[AgentStatus]:
        """The latest published status of every agent of the MAS, in all processes."""

    # -- directory facilitator (agents.directory) --------------------------------------------------
    def local_registrations(self, subscribed: tuple[str, str] | None = None) -> dict[str, list[str]]:
        """{agent: services} of the registered agents of this process that have any; ``subscribed``: the
        asker is agent (subscriber, service) of another process, which the directory remembers."""
        source = self.registrations
        if source is None:
            return {}
        if subscribed is not None and subscribed[0] in self._agents:
            subscribed = None  # our own agent: the directory tells it directly
        return {agent: list(services) for agent, services in source(subscribed).items()
                if services and agent in self._agents}

    @abstractmethod
    def remote_registrations(self, timeout: float = QUERY_TIMEOUT,
                             subscribe: tuple[str, str] | None = None) -> dict[str, list[str]]:
        """{agent: services} of the agents of the other processes of the MAS, each checked (signed by
        that agent in the secure profile); waits at most ``timeout`` for a process that does not answer.
        ``subscribe`` = (agent of this process, service): each process that answers also learns that
        the agent subscribes to the service, in one step with its answer (``local_registrations``)."""

    @abstractmethod
    def announce_subscription(self, agent: str, service: str) -> None:
        """Let the other processes know that ``agent`` (of this process) subscribed to ``service``."""

    @abstractmethod
    def withdraw_subscription(self, agent: str, service: str) -> None: ...

    @abstractmethod
    def on_subscription(self, callback: Callable[[str, str, bool], None]) -> None:
        """``callback(agent, service, present)`` (on a thread of the transport, never a network
        thread: it may send) for each subscription of an agent of another process: those there are
        now, then each that comes or goes, each change once."""

    # -- what a concrete transport provides ------------------------------------------------------
    @abstractmethod
    def _open(self) -> None: ...

    @abstractmethod
    def _close(self) -> None: ...

    @abstractmethod
    def _attach(self, agent: str) -> None:
        """Start receiving for ``agent``, then announce its presence (in that order)."""

    @abstractmethod
    def _detach(self, agent: str) -> None: ...

    @abstractmethod
    def _put(self, receiver: str, envelope: Envelope, encoded: "_Encoded") -> bool:
        """Send to a receiver outside this transport; False when nobody listens for it.
        ``encoded()`` gives the wire bytes, encoded once per envelope."""

    @abstractmethod
    def _ask_claims(self, name: str, timeout: float) -> dict[Claimant, bool]:
        """The claims the processes of the MAS hold on ``name`` ({claimant: won}), read from each process's
        ``NameClaims`` after every one has answered (``NameUndecided`` when not all did within ``timeout``)."""

    @abstractmethod
    def _publish_control(self, message: dict[str, Any]) -> None: ...

    @abstractmethod
    def _publish_status(self, status: AgentStatus) -> None: ...
