"""The Zenoh transport: ONE Zenoh session per process, shared by every agent of that process.

Per agent: a subscriber on ``faultmas/<mas>/agent/<name>/inbox`` and a liveliness token
``faultmas/<mas>/alive/<name>`` (declared after the subscriber, so whoever sees the token can already
reach the inbox). Per process: a liveliness subscriber with history (presence), a subscriber on
``faultmas/<mas>/control``, one on ``faultmas/<mas>/status/*`` and a queryable there that answers
with the latest status of the local agents (in the secure profile a status is signed by its agent and a
receiver refuses any other); a queryable on ``faultmas/<mas>/df/*`` that answers with the directory
facilitator's registrations of the local agents (``registrations``). Per registration a liveliness token
``faultmas/<mas>/provides/<agent>/<service>``, which other processes' subscribers watch (see
``agents.directory`` for why both). Messages are put reliably with congestion control
BLOCK on a cached publisher per receiver (a burst from the agents' thread in batches, see
``outbox``); agents of this process are served without the network.
"""
from __future__ import annotations

import json
import queue
import threading
from typing import Any, Callable

from agents.transport import keys
from agents.transport.base import Transport, log
from agents.transport.config import ZenohOptions, build_config, listen_endpoints
from agents.transport.envelope import DEFAULT_MAX_SIZE, BadMessage, Envelope
from agents.transport.registrations import QUERY_TIMEOUT, encode_services, new_nonce, open_services
from agents.transport.status import AgentStatus


INBOX_CAPACITY = 8192
"""Samples an inbox holds before Zenoh stops taking more for it (reliable puts then wait: no loss)."""


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
        self._tokens: dict[str, Any] = {}
        self._statuses: dict[str, AgentStatus] = {}
        self._declared: list[Any] = []
        self._provided: dict[tuple[str, str], Any] = {}              # (agent, service) -> liveliness token
        self._watches: dict[str, list[Callable[[str], None]]] = {}   # service -> callbacks
        self._watch_queue: queue.SimpleQueue = queue.SimpleQueue()  # (agent, service) announced; None: stop
        self._watch_thread: threading.Thread | None = None
        self._announced: set[tuple[str, str]] = set()   # tokens seen present (history and live may repeat one)
        self._announced_lock = threading.Lock()

    def _open(self) -> None:
        import zenoh

        if self.session is None:
            config = build_config(self.options)
            self.endpoints = listen_endpoints(config)
            self.session = zenoh.open(config)
        liveliness = self.session.liveliness()
        self._declared = [
            liveliness.declare_subscriber(keys.alive_pattern(self.mas), self._on_alive, history=True),
            self.session.declare_subscriber(keys.control_key(self.mas), self._on_control),
            self.session.declare_subscriber(keys.status_pattern(self.mas), self._on_status),
            self.session.declare_queryable(keys.status_pattern(self.mas), self._on_status_query),
            self.session.declare_queryable(keys.df_pattern(self.mas), self._on_df_query),
        ]
        self._control_publisher = self.session.declare_publisher(
            keys.control_key(self.mas), congestion_control=zenoh.CongestionControl.BLOCK,
            reliability=zenoh.Reliability.RELIABLE)

    def _close(self) -> None:
        self._watch_queue.put(None)
        for entity in [*self._publishers.values(), self._control_publisher, *self._provided.values(), *self._declared]:
            try:
                entity.undeclare()
            except Exception:  # already gone with the session
                pass
        self._publishers.clear()
        self._provided.clear()
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
        threading.Thread(target=self._drain, args=(agent, subscriber.handler, key), daemon=True,
                         name=f"faultmas-inbox-{agent}").start()
        self._tokens[agent] = self.session.liveliness().declare_token(keys.alive_key(self.mas, agent))

    def _drain(self, agent: str, channel: Any, key: str) -> None:
        """Take the samples of one inbox in batches, in a thread of ours. A Zenoh callback needs the
        GIL once per sample, and waits for it while the agents' thread reasons (up to the 5 ms
        switch interval): one sample per wait. Here the samples queue in Zenoh's channel without
        the GIL, and each time this thread gets the GIL it handles every sample waiting."""
        receive = self.receive_bytes
        try:
            sample = channel.recv()  # blocks without the GIL; ends when the subscriber goes
            while True:
                while sample is not None:
                    try:
                        receive(agent, sample.payload.to_bytes(), key)
                    except Exception:  # never lose the inbox over one message
                        log.exception("inbox of %s: a received message could not be handled", agent)
                    sample = channel.try_recv()
                sample = channel.recv()
        except Exception as exc:  # ZError "channel is empty and closed": undeclared or session closed
            if self._inboxes.get(agent) is not None and self._opened:
                log.debug("inbox of %s closed: %s", agent, exc)

    def _detach(self, agent: str) -> None:
        for (provider, service) in [k for k in self._provided if k[0] == agent]:
            self.withdraw(provider, service)
        for table in (self._tokens, self._inboxes):  # presence first: nobody should send any more
            entity = table.pop(agent, None)
            if entity is not None:
                entity.undeclare()
        self._statuses.pop(agent, None)

    def _put(self, receiver: str, envelope: Envelope, encoded: Callable[[], bytes]) -> bool:
        publisher = self._publishers.get(receiver)
        if publisher is None:
            publisher = self._publisher(receiver)
        # A client learns of remote subscribers lazily (through its router's interest replies), so a
        # receiver whose liveliness token is seen counts as reachable even before matching says so.
        if not (self._presence.is_alive(receiver) or publisher.matching_status.matching):
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

    # -- network callbacks (Zenoh threads: never block, never raise) -----------------------------
    def _on_alive(self, sample: Any) -> None:
        import zenoh

        agent = keys.last_chunk(str(sample.key_expr))
        self._presence.update(agent, sample.kind == zenoh.SampleKind.PUT)

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

        def agent_of(document: bytes) -> Any:
            try:
                data = json.loads(document)
            except (ValueError, RecursionError) as exc:
                raise BadMessage("not_json", str(exc)[:80]) from None
            return data.get("agent") if isinstance(data, dict) else None

        document, seq = self.identity.open(payload, agent_of)
        status = AgentStatus.decode(document)
        self.identity.check_fresh(status.agent, "status", seq)
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

    # -- directory facilitator --------------------------------------------------------------------
    def _on_df_query(self, query: Any) -> None:
        import zenoh

        asked = zenoh.KeyExpr(str(query.key_expr))
        nonce = query.payload.to_bytes().decode(errors="replace")[:64] if query.payload is not None else ""
        for agent, services in self.local_registrations().items():
            key = keys.df_key(self.mas, agent)
            if asked.intersects(zenoh.KeyExpr(key)):
                query.reply(key, encode_services(self.mas, agent, services, nonce, self.identity))

    def provide(self, agent: str, service: str) -> None:
        self.withdraw(agent, service)  # a new token: subscribers elsewhere see it appear again
        key = keys.provides_key(self.mas, agent, service)
        self._provided[(agent, service)] = self.session.liveliness().declare_token(key)

    def withdraw(self, agent: str, service: str) -> None:
        token = self._provided.pop((agent, service), None)
        if token is not None:
            token.undeclare()

    def remote_registrations(self, timeout: float = QUERY_TIMEOUT) -> dict[str, list[str]]:
        return self._query_registrations(keys.df_pattern(self.mas), timeout)

    def _query_registrations(self, key: str, timeout: float) -> dict[str, list[str]]:
        import zenoh

        nonce = new_nonce()
        found: dict[str, list[str]] = {}
        # every reply, unconsolidated: an outsider's reply on an agent's key must not displace the agent's
        for reply in self.session.get(key, payload=nonce, timeout=timeout,
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

    def watch_registrations(self, service: str, callback: Callable[[str], None]) -> None:
        callbacks = self._watches.get(service)
        if callbacks is not None:
            callbacks.append(callback)
            return
        self._watches[service] = [callback]
        if self._watch_thread is None:
            self._watch_thread = threading.Thread(target=self._check_announcements, daemon=True,
                                                  name="faultmas-df-watch")
            self._watch_thread.start()
        self._declared.append(self.session.liveliness().declare_subscriber(
            keys.provides_pattern(self.mas, service), lambda sample: self._on_provides(sample, service),
            history=True))

    def _on_provides(self, sample: Any, service: str) -> None:
        import zenoh

        agent = keys.provider_of(str(sample.key_expr))
        with self._announced_lock:
            if sample.kind != zenoh.SampleKind.PUT:  # withdrawn, or its process died: Jason tells nobody
                self._announced.discard((agent, service))
                return
            if (agent, service) in self._announced:
                return  # the same token seen twice (history and live), not a new registration
            self._announced.add((agent, service))
        if agent not in self._agents:
            self._watch_queue.put((agent, service))

    def _check_announcements(self) -> None:
        """Believe an announced registration only once the agent's own process confirms it (signed by
        the agent in the secure profile): a liveliness token is a hint anyone on the network can declare.
        On a thread of ours: a query from a Zenoh callback would wait on Zenoh's own threads."""
        while True:
            item = self._watch_queue.get()
            if item is None:
                return
            agent, service = item
            try:
                confirmed = self._query_registrations(keys.df_key(self.mas, agent), QUERY_TIMEOUT)
            except Exception as exc:  # the session closed meanwhile
                log.debug("directory: cannot confirm %s's registration: %s", agent, exc)
                continue
            if service not in confirmed.get(agent, ()):
                if agent not in confirmed:
                    log.info("directory: %s announced service %r but does not confirm it (withdrawn since, "
                             "or not announced by %s)", agent, service, agent)
                continue
            for callback in list(self._watches.get(service, ())):
                try:
                    callback(agent)
                except Exception:
                    log.exception("directory: a watcher of %r failed", service)

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
