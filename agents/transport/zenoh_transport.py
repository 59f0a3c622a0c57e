"""The Zenoh transport: ONE Zenoh session per process, shared by every agent of that process.

Per agent: a subscriber on ``faultmas/<mas>/agent/<name>/inbox`` and a liveliness token
``faultmas/<mas>/alive/<name>`` (declared after the subscriber, so whoever sees the token can already
reach the inbox). Per process: a liveliness subscriber with history (presence), a subscriber on
``faultmas/<mas>/control``, one on ``faultmas/<mas>/status/*`` and a queryable there that answers
with the latest status of the local agents (in the secure profile a status is signed by its agent and a
receiver refuses any other); a queryable on ``faultmas/<mas>/df/*`` that answers with the directory
facilitator's registrations of the local agents (``registrations``), and a liveliness subscriber with
history on ``faultmas/<mas>/subscribes/*/*``, the subscriptions of other processes' agents (a token per
``.df_subscribe``; see ``agents.directory``). In the secure profile a token alone proves nothing (anyone
may declare one): an agent is present while its token is up and its signed heartbeats keep coming
(``proved_presence``), and a subscription counts while its token is up and its agent's signed heartbeats list
it; a directory query that says who subscribes is signed by that agent. Messages are put reliably with congestion control
BLOCK on a cached publisher per receiver (a burst from the agents' thread in batches, see
``outbox``); agents of this process are served without the network.

Order across subscribers (zenoh-python runs each subscriber's callbacks on a thread of its own): the liveliness
callbacks run on Zenoh's own thread, so an agent's join and the token saying who made it are seen before its
messages that came after them; a leave, and a control message about one of our agents (``kill``), go through the
inboxes (``inbox_barrier``) and come after the messages that came before them.
"""
from __future__ import annotations

import json
import queue
import threading
import time
from typing import Any, Callable

from agents.transport import keys
from agents.transport.base import Transport, log
from agents.transport.config import ZenohOptions, build_config, listen_endpoints
from agents.transport.envelope import DEFAULT_MAX_SIZE, BadMessage, Envelope, is_valid_name
from agents.transport.identity import claimed_agent
from agents.transport.inbox_barrier import InboxBarriers
from agents.transport.name_claims import Claimant, NameUndecided, decode_claim, encode_claim
from agents.transport.proved_presence import HEARTBEAT, LEASE, ProvedPresence
from agents.transport.registrations import QUERY_TIMEOUT, encode_services, new_nonce, open_services
from agents.transport.status import AgentStatus
from robot_bridge.failure_log import FailureLog


INBOX_CAPACITY = 8192
"""Samples an inbox holds before Zenoh stops taking more for it (reliable puts then wait: no loss)."""
MAX_CLAIMS = 4096
"""Subscription tokens of other processes' agents a process keeps in the secure profile (each a claim until
the agent's heartbeats list it); more are refused, so an outsider's tokens cannot grow its memory."""
TO_AN_AGENT = frozenset({"kill"})
"""Control commands for one agent (its name in ``agent``): its process hands them over after the messages sent to
the agent before them (``inbox_barrier``), as they would be in one process."""
DRAIN_JOIN_TIMEOUT = 10.0
"""Seconds ``unregister``/``close`` wait for an inbox thread to hand over what it holds and end."""


class ZenohTransport(Transport):
    """A ``Transport`` over a Zenoh session (its own, or one the process already has)."""

    def __init__(self, mas: str, options: ZenohOptions | None = None, *, session: Any = None,
                 max_message_size: int = DEFAULT_MAX_SIZE, identity: Any = None) -> None:
        super().__init__(mas, max_message_size=max_message_size, identity=identity)
        self.options = options or ZenohOptions()
        self.session = session
        self._owns_session = session is None
        self.endpoints: list[str] = []
        self._publishers: dict[str, Any] = {}
        self._publish_lock = threading.Lock()
        self._inboxes: dict[str, Any] = {}
        self._drains: dict[str, threading.Thread] = {}
        self._tokens: dict[str, Any] = {}
        self._created_tokens: dict[str, Any] = {}   # agent made at run time -> its 'created' token
        self._departed: set[str] = set()   # agents whose liveliness token went (and has not come back)
        self._barriers = InboxBarriers(self._put_marker)   # events handed over behind the messages before them
        self._statuses: dict[str, AgentStatus] = {}
        self._declared: list[Any] = []
        # the secure profile: presence needs a signed proof besides the token
        self._proof = ProvedPresence(self._presence.update) if self.identity is not None else None
        self._heartbeats_done = threading.Event()
        self._subscribed: dict[tuple[str, str], Any] = {}   # (agent, service) -> liveliness token
        self._subscriptions: set[tuple[str, str]] = set()   # remote ones seen present (history may repeat one)
        self._subscription_callbacks: list[Callable[[str, str, bool], None]] = []
        self._subscription_lock = threading.Lock()
        self._subscription_queue: queue.SimpleQueue = queue.SimpleQueue()  # changes to report; None: stop
        self._subscription_thread: threading.Thread | None = None
        # the secure profile: subscription tokens seen (claims; 1 once refused) and each agent's subscriptions its
        # last signed heartbeat listed (with its time)
        self._claims: dict[tuple[str, str], int] = {}
        self._listed: dict[str, tuple[frozenset, float]] = {}

    def _open(self) -> None:
        import zenoh

        if self.session is None:
            config = build_config(self.options)
            self.endpoints = listen_endpoints(config)
            self.session = zenoh.open(config)
        liveliness = self.session.liveliness()
        # Liveliness called on Zenoh's own thread (not ``indirect``, where each subscriber's callbacks run on a thread
        # of their own, which may lag behind the inboxes' threads): an agent is known alive, or made at run time,
        # before its first message, which came after its token, is handed over (``inbox_barrier`` for the end)
        self._declared = [
            liveliness.declare_subscriber(keys.alive_pattern(self.mas),
                                          zenoh.handlers.Callback(self._on_alive, indirect=False), history=True),
            self.session.declare_subscriber(keys.control_key(self.mas), self._on_control),
            self.session.declare_subscriber(keys.status_pattern(self.mas), self._on_status),
            self.session.declare_queryable(keys.status_pattern(self.mas), self._on_status_query),
            self.session.declare_queryable(keys.df_pattern(self.mas), self._on_df_query),
            self.session.declare_queryable(keys.claim_pattern(self.mas), self._on_claim_query),
            liveliness.declare_subscriber(keys.subscribes_pattern(self.mas), self._on_subscribes, history=True),
            liveliness.declare_subscriber(keys.created_pattern(self.mas),
                                          zenoh.handlers.Callback(self._on_created, indirect=False), history=True),
        ]
        self._subscription_thread = threading.Thread(target=self._report_subscriptions, daemon=True,
                                                     name="faultmas-df-subscriptions")
        self._subscription_thread.start()
        self._control_publisher = self.session.declare_publisher(
            keys.control_key(self.mas), congestion_control=zenoh.CongestionControl.BLOCK,
            reliability=zenoh.Reliability.RELIABLE)
        if self._proof is not None:
            self._declared.append(self.session.declare_subscriber(keys.heartbeat_pattern(self.mas), self._on_heartbeat))
            self._heartbeats_done.clear()
            threading.Thread(target=self._heartbeats, daemon=True, name="faultmas-heartbeats").start()

    def _close(self) -> None:
        self._heartbeats_done.set()
        self._subscription_queue.put(None)
        for entity in [*self._publishers.values(), self._control_publisher, *self._subscribed.values(),
                       *self._created_tokens.values(), *self._declared]:
            try:
                entity.undeclare()
            except Exception:  # already gone with the session
                pass
        self._publishers.clear()
        self._subscribed.clear()
        self._declared = []
        if self._owns_session:
            self.session.close()
            self.session = None

    # -- agents ----------------------------------------------------------------------------------
    def _attach(self, agent: str) -> None:
        import zenoh

        key = keys.inbox_key(self.mas, agent)
        subscriber = self.session.declare_subscriber(key, zenoh.handlers.FifoChannel(INBOX_CAPACITY))
        self._inboxes[agent] = subscriber
        drain = threading.Thread(target=self._drain, args=(agent, subscriber.handler, key), daemon=True,
                                 name=f"faultmas-inbox-{agent}")
        self._drains[agent] = drain
        drain.start()
        creator = self._creators.get(agent)
        if creator is not None:  # before its presence: whoever sees it alive can tell it is a member
            self._created_tokens[agent] = self.session.liveliness().declare_token(
                keys.created_key(self.mas, agent, creator))
        self._tokens[agent] = self.session.liveliness().declare_token(keys.alive_key(self.mas, agent))
        if self._proof is not None:
            self._heartbeat(agent)   # proved at once, not a heartbeat later (peers may be waiting for it)

    def _drain(self, agent: str, channel: Any, key: str) -> None:
        """Take the samples of one inbox in batches, in a thread of ours. A Zenoh callback needs the
        GIL once per sample, and waits for it while the agents' thread reasons (up to the 5 ms
        switch interval): one sample per wait. Here the samples queue in Zenoh's channel without
        the GIL, and each time this thread gets the GIL it handles every sample waiting."""
        receive = self.receive_bytes
        barriers = self._barriers
        try:
            sample = channel.recv()  # blocks without the GIL; ends when the subscriber goes
            while True:
                while sample is not None:
                    try:
                        attachment = sample.attachment
                        if attachment is not None and barriers.is_marker(marker := attachment.to_bytes()):
                            barriers.reached(agent, marker)   # an event queued behind what came before it
                        else:
                            receive(agent, sample.payload.to_bytes(), key)
                    except Exception:  # never lose the inbox over one message
                        log.exception("inbox of %s: a received message could not be handled", agent)
                    sample = channel.try_recv()
                sample = channel.recv()
        except Exception as exc:  # ZError "channel is empty and closed": undeclared or session closed
            if self._inboxes.get(agent) is not None and self._opened:
                log.debug("inbox of %s closed: %s", agent, exc)

    def _detach(self, agent: str) -> None:
        for (subscriber, service) in [k for k in self._subscribed if k[0] == agent]:
            self.withdraw_subscription(subscriber, service)
        for table in (self._tokens, self._inboxes, self._created_tokens):  # presence first: nobody should send any more
            entity = table.pop(agent, None)
            if entity is not None:
                entity.undeclare()
        self._statuses.pop(agent, None)
        self._join_drain(agent)
        self._barriers.release(agent)   # what its inbox held is handed over: nothing more to wait for

    def _put_marker(self, agent: str, attachment: bytes) -> bool:
        """Queue a marker (``inbox_barrier``) behind what ``agent``'s inbox holds; False if it has no inbox."""
        import zenoh

        if agent not in self._inboxes:
            return False
        try:
            self.session.put(keys.inbox_key(self.mas, agent), b"", attachment=attachment,
                             allowed_destination=zenoh.Locality.SESSION_LOCAL)
        except Exception:  # the session closing: nothing will be handed over any more
            log.debug("marker for the inbox of %s not put", agent, exc_info=True)
            return False
        return True

    def _join_drain(self, agent: str) -> None:
        """Wait for the inbox thread, which ends once its subscriber is undeclared. Left running, it
        may still be inside Zenoh's ``recv`` when the interpreter shuts down: on waking it would ask
        for the GIL, CPython would end the thread with ``pthread_exit``, and the forced unwind through
        Zenoh's Rust frames aborts the whole process ("FATAL: exception not rethrown", SIGABRT)."""
        drain = self._drains.pop(agent, None)
        if drain is not None and drain is not threading.current_thread():
            drain.join(timeout=DRAIN_JOIN_TIMEOUT)
            if drain.is_alive():
                log.warning("inbox thread of %s still running %.0f s after its inbox closed",
                            agent, DRAIN_JOIN_TIMEOUT)

    def _open_signed(self, agent: str, payload: bytes) -> Envelope:
        """The secure profile's check; a fresh envelope its sender signed proves the sender alive, as its heartbeat
        does: with its token up (seen before this message, which came after it) it is reported alive before its
        first message is handed over, not when its first heartbeat's callback gets round to it."""
        envelope = super()._open_signed(agent, payload)
        if envelope.mas == self.mas and agent in envelope.receivers and not self._presence.is_alive(envelope.sender):
            self._proof.proved(envelope.sender)   # checked fresh by the base (a replay proves nothing)
        return envelope

    def _put(self, receiver: str, envelope: Envelope, encoded: Callable[[], bytes]) -> bool:
        publisher = self._publishers.get(receiver)
        if publisher is None:
            publisher = self._publisher(receiver)
        # A client learns of remote subscribers lazily (through its router's interest replies), so a
        # receiver whose liveliness token is seen counts as reachable even before matching says so; one whose
        # token was seen to go is not, even while the end of its inbox is still on its way (a killed agent:
        # a send to it fails at once, not into an inbox about to close).
        if not self._presence.is_alive(receiver) and (
                receiver in self._departed or not publisher.matching_status.matching):
            return False
        self._send_payload(receiver, envelope, encoded(), publisher.put)
        return True

    def _publisher(self, receiver: str) -> Any:
        import zenoh

        with self._publish_lock:  # agents of this process may send from several threads
            publisher = self._publishers.get(receiver)
            if publisher is None:
                publisher = self.session.declare_publisher(
                    keys.inbox_key(self.mas, receiver),
                    congestion_control=zenoh.CongestionControl.BLOCK,
                    reliability=zenoh.Reliability.RELIABLE)
                self._publishers[receiver] = publisher
            return publisher

    def put_raw(self, receiver: str, payload: bytes) -> None:
        """Put arbitrary bytes on ``receiver``'s inbox (for tests and probes of the receiving side)."""
        self._publisher(receiver).put(payload)

    # -- heartbeats (the secure profile) ----------------------------------------------------------
    def _heartbeat(self, agent: str) -> None:
        if self.identity.can_sign(agent):
            services = sorted(service for subscriber, service in list(self._subscribed) if subscriber == agent)
            document = json.dumps({"agent": agent, "subscribes": services} if services else {"agent": agent},
                                  separators=(",", ":")).encode()
            try:
                self.session.put(keys.heartbeat_key(self.mas, agent), self.identity.seal(agent, document))
            except Exception:  # the session closing: the thread ends with it
                log.debug("heartbeat of %s not put", agent, exc_info=True)

    def _heartbeats(self) -> None:
        """Every ``HEARTBEAT`` seconds: each local agent's signed heartbeat, then the leases checked."""
        failures = FailureLog(log, "heartbeats and leases")   # one bad round must not end them: peers would
        while not self._heartbeats_done.wait(HEARTBEAT):    # see this process's agents die of silence
            with failures.contained():
                for agent in list(self._tokens):
                    self._heartbeat(agent)
                self._proof.expire()
                for agent, service in list(self._claims):
                    self._settle_subscription(agent, service)

    def _on_heartbeat(self, sample: Any) -> None:
        key = str(sample.key_expr)
        try:
            document, seq = self.identity.open(sample.payload.to_bytes(), claimed_agent)
            agent = claimed_agent(document)
            if agent != keys.last_chunk(key):
                raise BadMessage("bad_signature", f"a heartbeat of {agent} put on {key}", agent)
            self.identity.check_fresh(agent, "heartbeat", seq)
        except BadMessage as bad:
            self._drop(bad.reason, key, bad.sender, bad.detail)
            return
        self._proof.proved(agent)
        listed = json.loads(document).get("subscribes")
        self._subscriptions_listed(agent, frozenset(s for s in listed if isinstance(s, str))
                                   if isinstance(listed, list) else frozenset())

    # -- network callbacks (Zenoh threads: never block, never raise) -----------------------------
    def _on_alive(self, sample: Any) -> None:
        import zenoh

        agent = keys.last_chunk(str(sample.key_expr))
        if sample.kind == zenoh.SampleKind.PUT:
            self._departed.discard(agent)
            self._token(agent, True)
        elif not self._presence.is_alive(agent):   # nobody to report gone (a claim withdrawn): at once
            self._departed.add(agent)
            self._token(agent, False)
        else:   # reported once every local inbox has handed over what the agent sent before it went
            self._departed.add(agent)
            self._barriers.after(list(self._inboxes), lambda: agent in self._departed and self._token(agent, False))

    def _token(self, agent: str, up: bool) -> None:
        if self._proof is not None:   # the secure profile: a token is a claim until a signed heartbeat proves it
            self._proof.token(agent, up)
        else:
            self._presence.update(agent, up)

    def _on_created(self, sample: Any) -> None:
        """A ``created/<agent>/<creator>`` token appeared (``creator_of``; its end changes nothing)."""
        import zenoh

        where = str(sample.key_expr)
        agent, creator = where.rsplit("/", 2)[-2:]
        if not (is_valid_name(agent) and is_valid_name(creator)):
            self._drop("bad_created", where, None, "expected created/<agent>/<creator>")
            return
        if sample.kind == zenoh.SampleKind.PUT:
            self._created(agent, creator)

    def _on_control(self, sample: Any) -> None:
        payload = sample.payload.to_bytes()
        try:
            message = self._open_control(payload)
            if not isinstance(message, dict) or not isinstance(message.get("command"), str):
                raise ValueError("expected an object with a string 'command'")
        except BadMessage as bad:
            self._drop(bad.reason, str(sample.key_expr), bad.sender, bad.detail)
            return
        except (ValueError, RecursionError) as exc:
            self._drop("bad_control", str(sample.key_expr), None, str(exc)[:80])
            return
        agent = message.get("agent")
        if message["command"] in TO_AN_AGENT and isinstance(agent, str) and agent in self._inboxes:
            self._barriers.after([agent], lambda: self._control_received(message))   # behind the messages before it
            return
        self._control_received(message)

    def _open_control(self, payload: bytes) -> Any:
        """The control message in ``payload``. In the secure profile a signed one has its ``by`` proved
        (or is refused); an unsigned one loses its ``by``, a mere claim (a launcher proves itself with
        its token instead, see ``agents.zenoh_arch``)."""
        if self.identity is None or b',"sig":"' not in payload:
            message = json.loads(payload)
            if self.identity is not None and isinstance(message, dict):
                message.pop("by", None)
            return message
        return self.identity.open_control(payload)

    def _on_status(self, sample: Any) -> None:
        try:
            status = self._open_status(sample.payload.to_bytes())
        except BadMessage as bad:
            self._drop(bad.reason, str(sample.key_expr), bad.sender, bad.detail)
            return
        except ValueError as exc:
            self._drop("bad_status", str(sample.key_expr), None, str(exc)[:80])
            return
        self._status_received(status)

    def _open_status(self, payload: bytes) -> AgentStatus:
        """The status in ``payload``. In the secure profile it must be signed by the agent it is about and
        fresh (``BadMessage`` otherwise): a forged 'idle' could end a ``mas run`` while its agents work."""
        if self.identity is None:
            return AgentStatus.decode(payload)

        document, seq = self.identity.open(payload, claimed_agent)
        status = AgentStatus.decode(document)
        self.identity.check_fresh(status.agent, "status", seq)
        self._proof.proved(status.agent)
        return status

    def _sealed_status(self, status: AgentStatus) -> bytes:
        """``status`` as published: signed by its agent in the secure profile (a fresh seq each time)."""
        if self.identity is not None and self.identity.can_sign(status.agent):
            return self.identity.seal(status.agent, status.encode())
        return status.encode()

    def _on_status_query(self, query: Any) -> None:
        import zenoh

        asked = zenoh.KeyExpr(str(query.key_expr))
        for agent in list(self._agents):
            key = keys.status_key(self.mas, agent)
            if asked.intersects(zenoh.KeyExpr(key)):
                status = self._statuses.get(agent) or self.status_of(agent, busy=False)
                query.reply(key, self._sealed_status(status))

    # -- names made at run time (name_claims) -----------------------------------------------------
    def _on_claim_query(self, query: Any) -> None:
        """Answer with the claims this process holds on the name asked about (pending or won)."""
        import zenoh

        asked = zenoh.KeyExpr(str(query.key_expr))
        for name, claimant, won in self._name_claims.held():
            key = keys.claim_key(self.mas, name)
            if asked.intersects(zenoh.KeyExpr(key)):
                query.reply(key, encode_claim(name, claimant, won))

    def _ask_claims(self, name: str, timeout: float) -> dict[Claimant, bool]:
        """Ask every process of the MAS (this one too); a process that does not answer in time leaves the claim
        undecided (one that is gone is dropped by Zenoh: its link closes, or its lease ends)."""
        import zenoh

        claims: dict[Claimant, bool] = {}
        # every reply, unconsolidated: the processes all answer on the same key
        for reply in self.session.get(keys.claim_key(self.mas, name), timeout=timeout,
                                      consolidation=zenoh.ConsolidationMode.NONE):
            if reply.ok is None:
                raise NameUndecided(f"a process of the MAS did not answer within {timeout:.1f} s "
                                    f"({reply.err.payload.to_string()[:60]})")
            try:
                claimant, won = decode_claim(reply.ok.payload.to_bytes(), name)
            except BadMessage as bad:
                self._drop(bad.reason, str(reply.ok.key_expr), None, bad.detail)
                continue
            claims[claimant] = claims.get(claimant, False) or won
        return claims

    # -- directory facilitator --------------------------------------------------------------------
    def _on_df_query(self, query: Any) -> None:
        import zenoh

        asked = zenoh.KeyExpr(str(query.key_expr))
        try:
            request = json.loads(query.payload.to_bytes()) if query.payload is not None else None
            nonce, subscribed = request["nonce"], request.get("subscribe")
            if not isinstance(nonce, str) or len(nonce) > 64 or subscribed is not None and not (
                    isinstance(subscribed, list) and len(subscribed) == 2 and is_valid_name(subscribed[0])
                    and isinstance(subscribed[1], str)):
                raise ValueError("expected {\"nonce\": str[, \"subscribe\": [agent, service]]}")
        except (ValueError, TypeError, KeyError, RecursionError) as exc:
            self._drop("bad_df_query", str(query.key_expr), None, str(exc)[:80])
            return
        if subscribed is not None and self.identity is not None:
            # the secure profile: a query says who subscribes only when signed by that agent (else the search is
            # answered, the subscription refused: an outsider cannot subscribe a member to anything)
            try:
                _, seq = self.identity.open(query.payload.to_bytes(), lambda _document: subscribed[0])
                self.identity.check_fresh(subscribed[0], "df", seq)
            except BadMessage as bad:
                self._drop(bad.reason, str(query.key_expr), None if bad.reason == "unsigned" else bad.sender,
                           f"a directory subscription of {subscribed[0]}")
                subscribed = None
        registrations = self.local_registrations(tuple(subscribed) if subscribed is not None else None)
        for agent, services in registrations.items():
            key = keys.df_key(self.mas, agent)
            if asked.intersects(zenoh.KeyExpr(key)):
                query.reply(key, encode_services(self.mas, agent, services, nonce, self.identity))

    def remote_registrations(self, timeout: float = QUERY_TIMEOUT,
                             subscribe: tuple[str, str] | None = None) -> dict[str, list[str]]:
        import zenoh

        nonce = new_nonce()
        request = {"nonce": nonce} if subscribe is None else {"nonce": nonce, "subscribe": list(subscribe)}
        payload: str | bytes = json.dumps(request, separators=(",", ":"))
        if subscribe is not None and self.identity is not None and self.identity.can_sign(subscribe[0]):
            payload = self.identity.seal(subscribe[0], payload.encode())   # who subscribes, proved
        found: dict[str, list[str]] = {}
        # every reply, unconsolidated: an outsider's reply on an agent's key must not displace the agent's
        for reply in self.session.get(keys.df_pattern(self.mas), payload=payload, timeout=timeout,
                                      consolidation=zenoh.ConsolidationMode.NONE):
            if reply.ok is None:
                continue
            where = str(reply.ok.key_expr)
            if keys.last_chunk(where) in self._agents:
                continue  # this process's own agents: the local directory has them
            try:
                agent, services = open_services(reply.ok.payload.to_bytes(), self.mas, nonce, self.identity,
                                                self.max_message_size)
            except BadMessage as bad:
                self._drop(bad.reason, where, bad.sender, bad.detail)
                continue
            if keys.last_chunk(where) != agent:
                self._drop("bad_registration", where, agent, "the document names another agent")
                continue
            found[agent] = services
        return found

    def announce_subscription(self, agent: str, service: str) -> None:
        if (agent, service) not in self._subscribed:
            self._subscribed[(agent, service)] = None   # listed by every heartbeat from now on
            if self._proof is not None:
                self._heartbeat(agent)   # the proof before the token: a heartbeat after it that lacks it is no proof
            self._subscribed[(agent, service)] = self.session.liveliness().declare_token(
                keys.subscribes_key(self.mas, agent, service))

    def withdraw_subscription(self, agent: str, service: str) -> None:
        token = self._subscribed.pop((agent, service), None)
        if token is not None:
            token.undeclare()

    def on_subscription(self, callback: Callable[[str, str, bool], None]) -> None:
        with self._subscription_lock:
            self._subscription_callbacks.append(callback)
            now = sorted(self._subscriptions)
        for agent, service in now:
            self._subscription_queue.put((agent, service, True, callback))

    def _on_subscribes(self, sample: Any) -> None:
        import zenoh

        where = str(sample.key_expr)
        try:
            agent, service = keys.subscription_of(where)
        except ValueError as exc:
            self._drop("bad_subscription", where, None, str(exc)[:80])
            return
        if agent in self._agents:
            return  # this process's own: its directory knows them
        present = sample.kind == zenoh.SampleKind.PUT
        if self.identity is not None:   # the secure profile: a token is a claim, the agent's heartbeats prove it
            if agent not in self.identity.members:
                if present:
                    self._drop("unknown_sender", where, agent, "a subscription token of no member")
                return
            with self._subscription_lock:
                full = present and (agent, service) not in self._claims and len(self._claims) >= MAX_CLAIMS
                if present and not full:
                    self._claims.setdefault((agent, service), 0)
                elif not present:
                    self._claims.pop((agent, service), None)
            if full:   # memory stays bounded whatever tokens an outsider declares
                self._drop("bad_subscription", where, agent, f"more than {MAX_CLAIMS} subscription tokens")
                return
            self._settle_subscription(agent, service)
            return
        self._subscription_changed(agent, service, present)

    def _subscriptions_listed(self, agent: str, services: frozenset) -> None:
        """A signed heartbeat of ``agent`` listed its subscriptions: the claims it lists count; a claim seen before a
        heartbeat that does not list it is refused with a log line (an agent's process puts a heartbeat listing a
        subscription before it declares its token), and counts if a later heartbeat lists it."""
        if agent in self._agents:
            return  # this process's own: its directory knows them (a token seen before the agent registered)
        unproved = []
        with self._subscription_lock:
            self._listed[agent] = (services, time.monotonic())
            claims = [(a, s) for (a, s) in self._claims if a == agent]
            for claim in claims:
                if claim[1] not in services and not self._claims[claim]:
                    self._claims[claim] = 1     # refused once: one log line per claim
                    unproved.append(claim)
        for subscriber, service in unproved:
            self._drop("unsigned", keys.subscribes_key(self.mas, subscriber, service), subscriber,
                       f"a subscription token that no signed heartbeat of {subscriber} lists")
        for subscriber, service in claims:
            self._settle_subscription(subscriber, service)

    def _settle_subscription(self, agent: str, service: str) -> None:
        """A subscription counts while its token is up and a signed heartbeat within the lease lists it."""
        with self._subscription_lock:
            services, when = self._listed.get(agent, (frozenset(), -LEASE))
            present = (agent, service) in self._claims and service in services and time.monotonic() - when <= LEASE
        self._subscription_changed(agent, service, present)

    def _subscription_changed(self, agent: str, service: str, present: bool) -> None:
        with self._subscription_lock:
            if ((agent, service) in self._subscriptions) == present:
                return  # seen twice (history and live): one change
            (self._subscriptions.add if present else self._subscriptions.discard)((agent, service))
            if self._subscription_callbacks:
                self._subscription_queue.put((agent, service, present, None))

    def _report_subscriptions(self) -> None:
        """Hand subscription changes to the callbacks on a thread of ours: they send messages, which a
        Zenoh callback must not (a blocking put there could wait on Zenoh's own threads)."""
        while True:
            item = self._subscription_queue.get()
            if item is None:
                return
            agent, service, present, only = item
            for callback in [only] if only is not None else list(self._subscription_callbacks):
                try:
                    callback(agent, service, present)
                except Exception:
                    log.exception("directory: a subscription callback failed")

    # -- control and status ----------------------------------------------------------------------
    def _publish_control(self, message: dict[str, Any]) -> None:
        if self.identity is not None and self.identity.can_sign(str(message.get("by"))):
            self._control_publisher.put(self.identity.seal_control(message))
        else:
            self._control_publisher.put(json.dumps(message, separators=(",", ":")))

    def _publish_status(self, status: AgentStatus) -> None:
        self._statuses[status.agent] = status
        self.session.put(keys.status_key(self.mas, status.agent), self._sealed_status(status))

    def collect_status(self, timeout: float = 1.0) -> list[AgentStatus]:
        statuses = {}
        for reply in self.session.get(keys.status_pattern(self.mas), timeout=timeout):
            if reply.ok is None:
                continue
            try:
                status = self._open_status(reply.ok.payload.to_bytes())
            except BadMessage as bad:
                self._drop(bad.reason, str(reply.ok.key_expr), bad.sender, bad.detail)
                continue
            except ValueError as exc:
                log.warning("ignored a bad status reply on %s: %s", reply.ok.key_expr, exc)
                continue
            statuses[status.agent] = status
        return sorted(statuses.values(), key=lambda s: s.agent)
