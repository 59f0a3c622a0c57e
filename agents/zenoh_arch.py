"""Puts the agents of a ``LocalRuntime`` on a ``Transport`` (Zenoh, or the in-memory one in tests).

Outgoing: a ``Message`` to an agent that is not in this process becomes one ``Envelope`` whose content
is the AgentSpeak text of the term (``to_str``) and whose id / ``in_reply_to`` are the message's own,
so answers find the asking intention. Incoming: the envelope's content is parsed with the
interpreter's parser and the ``Message`` goes to ``agent.deliver``. A message that cannot be used
(unparsable content, plans from an untrusted sender) is dropped with one log line naming sender and
reason and counted, through the transport's ``report_drop`` (the transport already drops what does
not decode, is too large, names an unknown performative or comes from another MAS).

The directory facilitator (``.df_*``) reaches the other processes through ``agents.directory``; a
provider's notice to a subscriber here (``re`` = ``PROVIDER_NOTICE``) is checked and delivered from ``df``.

Presence becomes percepts: ``agent_alive(Name)`` is added when agent ``Name`` of the MAS appears on
the network and removed when it goes (its process exits, is killed, or its link lease expires), so
``+agent_alive(N)`` / ``-agent_alive(N)`` plans fire. An agent does not perceive itself.
"""
from __future__ import annotations

import hmac
import logging
import os
import threading
import time
from collections import OrderedDict
from functools import partial
from typing import Callable, Iterable

from agents.directory import PROVIDER_NOTICE, NetworkDirectory, notice_service
from agents.transport.base import Transport
from agents.transport.envelope import BadMessage, Envelope, make_envelope
from agents.transport.keys import check_name
from agents.transport.trust import CODE_PERFORMATIVES, TrustPolicy, is_member
from agentspeak.agent import Agent
from agentspeak.beliefs import SOURCE_PERCEPT
from agentspeak.communication import Message
from agentspeak.directory import DF_SENDER
from agentspeak.errors import FaultmasError
from agentspeak.ground_terms import read_ground_term
from agentspeak.parser import parse_term
from agentspeak.program import ADD, BEL, DEL, PlanTerm, Trigger
from agentspeak.runtime import LocalArch, LocalRuntime
from agentspeak.stdlib.registry import IAError
from agentspeak.terms import Literal, Term, is_ground, to_str

log = logging.getLogger("faultmas.agents")

PRESENCE_FUNCTOR = "agent_alive"
"""The percept ``agent_alive(Name)``: agent ``Name`` of this MAS is reachable right now."""

MEMBERS_ONLY = frozenset({"achieve", "unachieve", "tellHow", "untellHow"})
"""Performatives that make an agent act or change its plans: refused from non-members of a known MAS."""

LAUNCHER_TOKEN_ENV = "FAULTMAS_LAUNCHER_TOKEN"
"""The launcher of ``faultmas mas run --processes`` gives its children a random token in this variable
and puts it in its ``stop``: a stop from outside the MAS must know it (agents.distributed)."""

IDLE_GRACE = 0.01
"""Seconds the runtime must stay idle before 'idle' is published (a busy ring publishes nothing)."""

IDLE_COLLECT_S = 20.0
"""Seconds of wall time at least between two full garbage collections, each made when the agents go idle.
A suspended intention's objects refer to each other (a Suspend, its finish and on_done closures, the awaited
future), so they outlive it until Python's gc runs a full collection; an agent process holds ~55,000 objects
once loaded, and the gc's own rule (a full collection once those not yet fully collected number a quarter of
the rest) let ~20,000 garbage objects pile up between two, a level that rose as the agents ran (issue 22's
soak). Collected when idle, the garbage is one task's, and the cost (a few ms: 3.5 ms for 36,000 objects)
falls where nothing waits."""


class ContentCache:
    """Parsed message contents by text, for ground terms only (immutable, so safe to share), within a
    byte budget: the interpreter's parser costs ~75 µs per small term and repeated contents (status
    reports, positions) are common. Hostile input cannot grow it past ``max_bytes``."""

    def __init__(self, max_bytes: int = 4 * 1024 * 1024) -> None:
        self.max_bytes = max_bytes
        self._terms: OrderedDict[str, Term] = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()  # network threads of several agents may parse at once

    def parse(self, text: str) -> Term:
        """The term for ``text`` (``AslSyntaxError`` if it is not one). Ground contents the
        interpreter's fast reader handles (a few µs) are not worth a cache entry."""
        term = read_ground_term(text)
        if term is not None:
            return term
        term = self._terms.get(text)
        if term is not None:
            return term
        term = parse_term(text)
        if len(text) <= self.max_bytes // 16 and type(term) is not PlanTerm and is_ground(term):
            with self._lock:
                if text not in self._terms:
                    self._terms[text] = term
                    self._bytes += len(text)
                    while self._bytes > self.max_bytes:
                        old, _ = self._terms.popitem(last=False)
                        self._bytes -= len(old)
        return term


CONTENT_CACHE = ContentCache()


class NetworkArch(LocalArch):
    """``LocalArch`` whose MAS extends beyond this process: names, stop and trust come from the bridge.

    ``body``: the architecture the agent had before it joined the network (e.g. a ``RobotArch``); its
    ``perceive`` and ``act`` stay in force (``EmbodiedNetworkArch``), so a robot agent keeps its robot.
    An agent without a body keeps the default ``perceive``, which the reasoning cycle skips.
    """

    def __init__(self, runtime: LocalRuntime, bridge: "TransportBridge", body: LocalArch | None = None) -> None:
        super().__init__(runtime)
        self.bridge = bridge
        self.body = body

    @staticmethod
    def for_agent(runtime: LocalRuntime, bridge: "TransportBridge", body: LocalArch | None) -> "NetworkArch":
        return NetworkArch(runtime, bridge) if body is None else EmbodiedNetworkArch(runtime, bridge, body)

    def progress(self, agent: Agent, report) -> None:
        """``.progress``: published on the MAS's control key for the process that runs the MAS (signed by
        the agent in the secure profile)."""
        self.bridge.transport.publish_control("progress", **report.to_control())

    def all_names(self, agent: Agent) -> list[str]:
        return self.bridge.all_names()

    def stop_mas(self, agent: Agent, delay: float = 0.0, exit_code: int = 0) -> None:
        self.bridge.stop_mas(agent.name, delay, exit_code)

    def kill_agent(self, agent: Agent, name: str, delay: float = 0.0) -> bool:
        return self.runtime.kill_agent(name, delay) or self.bridge.kill_elsewhere(agent.name, name, delay)

    def accepts_plans_from(self, agent: Agent, sender: str) -> bool:
        return self.bridge.may_tell_how(sender)


class EmbodiedNetworkArch(NetworkArch):
    """A ``NetworkArch`` whose agent perceives and acts through its body (e.g. a robot)."""

    def perceive(self, agent: Agent):
        return self.body.perceive(agent)

    def act(self, agent: Agent, action: Literal):
        return self.body.act(agent, action)

    def environment_clock(self):
        return self.body.environment_clock()


class TransportBridge:
    """Connects every agent of ``runtime`` to ``transport``; ``attach`` once the agents are added.

    ``declared``: the agents of the project file (trusted to send plans, part of ``.all_names``);
    ``allowed_code_senders``: other agents the project allows to send plans; ``members``: every agent of
    the MAS when a project file says so (None: not known). Non-members may then not make an agent act
    or learn plans (``MEMBERS_ONLY``) nor stop the MAS; anyone may still tell and ask. Envelope senders
    are only what the sender claims (see ``trust``): this keeps out strangers that do not know the
    project, and a message claiming to come from one of this process's own agents (they never arrive
    over the network) is refused as forged. In the secure profile (``transport.identity``) the transport
    has already refused every message not signed by a member's key, so ``sender`` is proved.
    """

    def __init__(self, runtime: LocalRuntime, transport: Transport, *, declared: Iterable[str] = (),
                 allowed_code_senders: Iterable[str] = (), members: Iterable[str] | None = None) -> None:
        self.runtime = runtime
        self.transport = transport
        self.mas = transport.mas
        self.policy = TrustPolicy(transport.mas, frozenset(declared), frozenset(allowed_code_senders))
        self.members = None if members is None else frozenset(members) | self.policy.allowed_code_senders
        identity = getattr(transport, "identity", None)
        if identity is not None:  # the secure profile: the members are those whose keys the project lists
            self.members = (self.members or frozenset()) | identity.members
        self.published_idle: bool | None = None
        self.dead: set[str] = set()  # agents whose process the launcher saw die (control 'died')
        self.on_message = None
        """``on_message(direction, agent, message)``: sees each message to ('out', a ``Message``) or
        from ('in', an ``Envelope``) another process (the inspector keeps the last few)."""
        self.on_membership = None
        """``on_membership(name, agent)``: an agent of this process made at run time (``agent``) or killed (None),
        once it is on the network or off it (the inspector serves its mind)."""
        self._attached = False
        self._collected_at = time.monotonic()

    # -- set-up --------------------------------------------------------------------------------
    def attach(self) -> "TransportBridge":
        """Register the runtime's agents on the transport (announcing them) and route remote sends."""
        if self._attached:
            return self
        self.runtime.remote = self.send_remote
        self.runtime.directory = NetworkDirectory(self.runtime.tell_provider, self.transport,  # .df_* reach afar
                                                  self.runtime.route)
        self.transport.on_control(self._on_control)
        for agent in self.runtime.agents.values():
            self._join(agent)
        self.runtime.membership = self  # agents made or killed at run time come and go on the network too
        self.transport.on_presence(self._on_presence)
        self._attached = True
        return self

    def _join(self, agent: Agent, creator: str | None = None) -> None:
        body = agent.arch if type(agent.arch) is not LocalArch else None
        agent.arch = NetworkArch.for_agent(self.runtime, self, body)
        self.transport.register(agent.name, partial(self._on_envelope, agent), agent.wake, creator=creator)

    def detach(self) -> None:
        """Withdraw the agents from the network (others see ``-agent_alive``)."""
        self.runtime.membership = None
        for name in self.runtime.agents:
            self.transport.unregister(name)
        self.runtime.remote = None
        self._attached = False

    # -- agents made and killed at run time (``LocalRuntime.membership``) ----------------------
    def taken(self, name: str) -> bool:
        """A name ``.all_names`` lists (of the project and not gone, or alive anywhere): a new agent gets another."""
        return name in self._names()

    def admit(self, name: str) -> None:
        """A made agent is on the network under its name, so the name must be one a key expression can hold;
        in the secure profile it must sign as itself (see ``docs/language.md``, agents made at run time)."""
        try:
            check_name(name)
        except ValueError as exc:
            raise IAError("ia_failed", f"cannot create an agent of the MAS: {exc}") from None
        identity = getattr(self.transport, "identity", None)
        if identity is not None and not identity.can_sign(name):
            raise IAError("secure_profile", (
                f"cannot create agent {name} in the secure profile: every agent signs what it sends with its own "
                f"key, listed in the project (key=), and {name} has none; signed with its creator's key under its "
                f"own name its messages would be refused by every receiver as forged. Make it an agent of the "
                f"project (declared with its key=, started with the MAS), or run a project without key= options"))

    def joined(self, agent: Agent, creator: str) -> None:
        """On the network like a launched agent: its inbox, its presence, announced as made by ``creator`` (a
        member for the other processes as long as its creator is one)."""
        self._join(agent, creator)
        if self.on_membership is not None:
            self.on_membership(agent.name, agent)

    def left(self, name: str) -> None:
        """Killed: its last counters published (a launcher's message count stays whole), then off the network
        (its presence and inbox go; its registrations went with ``Directory.forget``)."""
        if name in self.transport.local_agents():
            self.transport.publish_status(name, busy=False)
            self.transport.unregister(name)
            if self.on_membership is not None:
                self.on_membership(name, None)

    # -- names and trust -----------------------------------------------------------------------
    def all_names(self) -> list[str]:
        """Agents of the project not seen gone, agents of this process and every agent alive on the network."""
        return sorted(self._names())

    def _names(self) -> set[str]:
        """A project's agent is listed before its process is seen (as Jason's platform creates every agent before
        any runs), and no longer once it has left: killed by ``.kill_agent``, ended, or its process died."""
        transport = self.transport
        return ((set(self.policy.declared_agents) - transport.departed_agents()) | set(self.runtime.agents)
                | transport.alive_agents())

    def may_tell_how(self, sender: str) -> bool:
        """As in Jason, every agent of the project may send plans, and so may those they made at run time."""
        return sender in self.runtime.agents or self.policy.may_tell_how(sender) or is_member(
            sender, self.policy.declared_agents | self.policy.allowed_code_senders, self.transport.creator_of)

    def is_member(self, name: str) -> bool:
        """An agent of the MAS (always, when no project says who is): of the project, of this process, or made
        at run time by one (in the secure profile: whose key the project lists)."""
        return self.members is None or name in self.runtime.agents or is_member(
            name, self.members, self.transport.creator_of)

    # -- outgoing ------------------------------------------------------------------------------
    def send_remote(self, message: Message) -> bool:
        """``LocalRuntime.remote``: send a message for an agent outside this process; False if unreachable."""
        try:
            envelope = make_envelope(self.mas, message.sender, (message.receiver,), message.performative,
                                     to_str(message.content), message.in_reply_to, message.msg_id)
        except BadMessage as bad:
            log.warning("[%s] cannot send %s to %s: %s", message.sender, message.performative,
                        message.receiver, bad)
            return True  # reported here; not an unknown receiver
        if self.on_message is not None:
            self.on_message("out", message.sender, message)
        return not self.transport.send(envelope)

    def kill_elsewhere(self, by: str, name: str, delay: float = 0.0) -> bool:
        """``.kill_agent`` of an agent of another process (Jason's agents may kill any agent of the MAS): its
        process kills it when told (a control message; signed by ``by`` in the secure profile). False when no
        agent of that name is alive anywhere."""
        if name not in self.transport.alive_agents():
            return False
        self.transport.publish_control("kill", agent=name, by=by, delay=delay)
        return True

    def _on_kill(self, message: dict) -> None:
        """Another process's agent killed one of ours: it dies in its own next turn (the runtime is not
        thread-safe), as it would by its own ``.kill_agent``."""
        by, name = message.get("by"), message.get("agent")
        agent = self.runtime.agents.get(name) if isinstance(name, str) else None
        if agent is None:
            return
        if self.members is not None and not (isinstance(by, str) and self.is_member(by)):
            self.transport.report_control_refused(message, "not_a_member")
            return
        agent.post_feedback(partial(self.runtime.kill_agent, name, control_delay(message)))

    def stop_mas(self, by: str, delay: float = 0.0, exit_code: int = 0) -> None:
        """``.stopMAS``: every process of the MAS (this one too) stops after ``delay`` seconds; the
        launcher exits with ``exit_code`` (``agents.distributed``)."""
        self.transport.publish_control("stop", by=by, delay=delay, code=exit_code)
        self.runtime.stop(delay, exit_code)

    # -- incoming (network threads: never block, never raise) ---------------------------------
    def _on_envelope(self, agent: Agent, envelope: Envelope) -> None:
        sender = envelope.sender
        if sender in self.runtime.agents:  # this process's agents are delivered to locally, never from afar
            self._refuse(agent, envelope, "forged_sender", f"{sender} is an agent of this process")
            return
        if (envelope.performative in MEMBERS_ONLY and not self.is_member(sender)
                and envelope.performative not in CODE_PERFORMATIVES  # plans: 'untrusted_code' below
                and envelope.in_reply_to not in agent.pending_asks):
            self._refuse(agent, envelope, "not_a_member", f"{envelope.performative} only from agents of the MAS")
            return
        if envelope.performative in CODE_PERFORMATIVES and not self.may_tell_how(envelope.sender) \
                and envelope.in_reply_to not in agent.pending_asks:  # an askHow answer is not refused
            self._refuse(agent, envelope, "untrusted_code", "plans only from agents declared in the project")
            return
        check = self.policy.extra_check
        if check is not None and not check(envelope):
            self._refuse(agent, envelope, "refused_by_policy")
            return
        try:
            content = CONTENT_CACHE.parse(envelope.content)
        except (FaultmasError, ValueError, RecursionError) as exc:
            detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            self._refuse(agent, envelope, "unparsable_content", detail[:100])
            return
        if envelope.in_reply_to == PROVIDER_NOTICE:
            self._on_provider_notice(agent, envelope, content)
            return
        if self.on_message is not None:
            self.on_message("in", agent.name, envelope)
        # no wake per message: the transport calls agent.wake once per batch
        agent.deliver(Message(envelope.sender, agent.name, envelope.performative, content,
                              msg_id=envelope.message_id, in_reply_to=envelope.in_reply_to), wake=False)

    def _on_provider_notice(self, agent: Agent, envelope: Envelope, content: Term) -> None:
        """A provider tells a subscriber of this process that it provides a service (``agents.directory``):
        delivered as Jason's DF tells it, from ``df``, if it is about its sender and the agent subscribed."""
        service = notice_service(envelope.sender, content) if envelope.performative == "tell" else None
        if service is None:
            self._refuse(agent, envelope, "bad_df_notice", "expected provider(<sender>, \"Service\")")
        elif agent.name not in self.runtime.get_directory().subscribers_of(service):
            self._refuse(agent, envelope, "not_subscribed", f"{agent.name} did not subscribe to {service[:60]!r}")
        else:
            if self.on_message is not None:
                self.on_message("in", agent.name, envelope)
            agent.deliver(Message(DF_SENDER, agent.name, "tell", content, msg_id=envelope.message_id), wake=False)

    def _refuse(self, agent: Agent, envelope: Envelope, reason: str, detail: str = "") -> None:
        agent.count_dropped(reason)
        self.transport.report_drop(envelope, agent.name, reason, detail)

    def _on_presence(self, name: str, alive: bool) -> None:
        for agent in list(self.runtime.agents.values()):
            if agent.name != name:
                change = partial(_presence_percept, agent, name, alive)
                agent.post_feedback(change if alive else _after_mail(agent, change))

    def _on_control(self, message: dict) -> None:
        if message.get("command") == "died" and self._from_launcher(message):
            self.dead.add(str(message.get("agent")))
            return
        if message.get("command") == "kill":
            self._on_kill(message)
            return
        if message.get("command") == "stop":
            by = message.get("by")
            if self.members is not None and not (isinstance(by, str) and self.is_member(by)) \
                    and not self._from_launcher(message):
                self.transport.report_control_refused(message, "not_a_member")
                return
            self.runtime.stop(control_delay(message))

    @staticmethod
    def _from_launcher(message: dict) -> bool:
        token = os.environ.get(LAUNCHER_TOKEN_ENV)
        return bool(token) and hmac.compare_digest(str(message.get("token", "")), token)

    def wait_for_peers(self, names: Iterable[str], timeout: float) -> bool:
        """Wait until every agent of ``names`` is reachable, or known dead (the launcher says so: a peer
        killed before it became reachable must not hold the others for the whole ``timeout``). False after
        ``timeout``, or at once when this process is told to stop: a peer that ended by ``.stopMAS`` before
        this one became reachable never will be, and its stop (or the launcher's, a signal) must not wait
        for the ``timeout`` (a run's launcher SIGKILLed such an agent after 6 s)."""
        deadline = time.monotonic() + timeout
        wanted = set(names)
        while True:
            if self.runtime.stop_requested():
                return False
            pending = wanted - self.dead
            if self.transport.wait_for_agents(pending, timeout=min(0.2, max(0.0, deadline - time.monotonic()))):
                if wanted & self.dead:
                    log.warning("agents %s died before they became reachable; starting without them",
                                ", ".join(sorted(wanted & self.dead)))
                return True
            if time.monotonic() >= deadline:
                return False

    # -- status and the run loop ---------------------------------------------------------------
    def _collect_garbage(self) -> None:
        """A full collection, now that the agents went idle, unless one ran less than ``IDLE_COLLECT_S`` ago."""
        now = time.monotonic()
        if now - self._collected_at >= IDLE_COLLECT_S:
            import gc
            gc.collect()
            self._collected_at = time.monotonic()

    def publish_status(self, busy: bool) -> None:
        """Publish every local agent as idle or busy with its message counters (for launchers)."""
        self.published_idle = not busy
        for name in self.runtime.agents:
            self.transport.publish_status(name, busy)

    def run(self, timeout: float | None = None) -> str:
        """Run the runtime until ``.stopMAS`` (any process) or ``timeout``: 'stopped' or 'timeout'.
        Never stops on idle (other processes may still send): publishes idle/busy instead.
        What the agents send to other processes meanwhile goes in batches, flushed whenever the
        runtime goes idle (and by the transport within a millisecond while it stays busy)."""
        with self.transport.batching():
            return self._run(timeout)

    def _run(self, timeout: float | None) -> str:
        deadline = None if timeout is None else time.monotonic() + timeout
        runtime = self.runtime
        flush = self.transport.flush
        self.publish_status(busy=True)
        while True:
            remaining = None if deadline is None else max(0.0, deadline - time.monotonic())
            why = runtime.run(timeout=remaining, stop_when_idle=True)
            flush()
            if why != "idle":
                return why
            if not self.published_idle and not runtime.wait_for_work(IDLE_GRACE):
                self.publish_status(busy=False)
                self._collect_garbage()
            remaining = None if deadline is None else max(0.0, deadline - time.monotonic())
            if remaining == 0.0:
                return "timeout"
            if runtime.wait_for_work(0.5 if remaining is None else min(remaining, 0.5)) and self.published_idle:
                self.publish_status(busy=True)


def control_delay(message: dict) -> float:
    """The seconds a ``stop`` or ``kill`` control message gives (``.stopMAS(D)``, ``.kill_agent(N, D)``); 0 for a
    missing field or one that is no positive number (a control message comes from another process)."""
    delay = message.get("delay", 0.0)
    return float(delay) if isinstance(delay, (int, float)) and not isinstance(delay, bool) and delay > 0 else 0.0


def _after_mail(agent: Agent, action: Callable[[], None]) -> Callable[[], None]:
    """``action`` once ``agent`` has read the messages in its mailbox now. An agent's leave is reported after the
    messages it sent before it went are in the mailboxes (``agents.transport.inbox_barrier``), but a cycle runs its
    feedback before it reads a message (as Jason perceives before it reads its mail): ``-agent_alive(d)`` would come
    before the last message of ``d``, handed over an instant before it. So it waits, a cycle at a time (a timer due
    at once runs in the next cycle, after this one read a message), until the first message is none of those."""
    held = list(agent.mailbox)   # the references keep their ids unique while they are held
    if not held:
        return action
    ids = {id(message) for message in held}

    def when_read() -> None:
        mailbox = agent.mailbox
        if mailbox and id(mailbox[0]) in ids:
            agent.add_timer(0.0, when_read)
        else:
            held.clear()
            action()
    return when_read


def _presence_percept(agent: Agent, name: str, alive: bool) -> None:
    """Add or remove the percept ``agent_alive(name)`` (in the agent's own thread)."""
    percept = Literal(PRESENCE_FUNCTOR, (Literal(name),), (SOURCE_PERCEPT,))
    if alive:
        added = agent.bb.add(percept)
        if added is not None:
            agent.post_external(Trigger(ADD, BEL, added))
    else:
        removed = agent.bb.remove(percept)
        if removed is not None:
            agent.post_external(Trigger(DEL, BEL, removed))
