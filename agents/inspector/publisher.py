"""The agent side of the inspector: state on demand, a change stream only while someone watches.

Per agent of the runtime (those made at run time too, from when they are made until they are killed: the
bridge's ``on_membership``), on the agent's transport session:

* a queryable on ``inspect/<agent>/state`` that answers with its mind (``snapshot.mind``; parameter
  ``summary`` for the team list, ``plans`` to add the plan library);
* a publisher on ``inspect/<agent>/stream`` whose matching listener starts one thread of this process
  while a subscriber exists: it puts the mind whenever the agent has cycled, at most every ``period``;
* a queryable on ``inspect/<agent>/control`` for ``pause``/``step``/``resume``, refused unless the MAS was
  started with ``allow_control`` (``--allow-pause``).

In the secure profile (the transport has an identity) every answer and every streamed mind is signed by its
agent, so a viewer with the project's keys shows only what the agent said; a ``pause``/``step``/``resume`` is
obeyed only when signed by a key the project lists (a member's or the environment's: whoever may already make
the agent act or feed its percepts may also hold it; ``faultmas inspect --identity``, or the run's own
inspector, which holds the environment's key) and fresh. Others are refused with a reason and one
rate-limited log line; an outsider can neither hold an agent nor show a forged mind.

Nothing of this runs in the agent's reasoning cycle: an agent nobody watches pays nothing per cycle
(``python -m benchmarks inspect`` measures it); the only standing cost is the last ``history`` messages
in and out of the process kept per agent (one deque append per message, formatted only when asked).
"""
from __future__ import annotations

import json
import logging
import queue
import threading
import time
from collections import deque
from typing import Any

from agents.inspector import keys, snapshot
from agents.inspector.observers import observers_of
from agents.inspector.pause import PauseGate
from agentspeak.terms import to_str

log = logging.getLogger("faultmas.inspector")

PERIOD = 0.1
"""Seconds between two puts of a watched agent's mind (at most; none while it does not cycle)."""
HISTORY = 50
COMMANDS = ("pause", "step", "resume")


class _Watched:
    """One agent as the publisher serves it."""

    def __init__(self, agent: Any, gate: PauseGate, history: int) -> None:
        self.agent = agent
        self.gate = gate
        self.messages: deque = deque(maxlen=history)
        self.watchers = False
        self.last_put: tuple | None = None
        self.stream: Any = None
        self.declared: list[Any] = []   # its Zenoh entities, undeclared when it goes


class MindPublisher:
    """Serves the minds of ``runtime``'s agents on ``transport`` (a ``ZenohTransport``, opened).
    ``bridge``: the ``TransportBridge`` whose messages are kept for the page (``on_message`` hook)."""

    def __init__(self, transport: Any, runtime: Any, bridge: Any = None, *, allow_control: bool = False,
                 history: int = HISTORY, period: float = PERIOD) -> None:
        self.transport, self.runtime, self.bridge = transport, runtime, bridge
        self.mas = transport.mas
        self.allow_control = allow_control
        self.period = period
        self.history = history
        self.agents: dict[str, _Watched] = {}
        self._wake = threading.Event()
        self._closed = threading.Event()
        self._thread: threading.Thread | None = None
        self._control_thread: threading.Thread | None = None
        self._controls: queue.SimpleQueue = queue.SimpleQueue()

    # -- life cycle ------------------------------------------------------------------------------
    def start(self) -> "MindPublisher":
        for agent in list(self.runtime.agents.values()):
            self.watch(agent)
        # pause and step wait for the agent's thread: not on Zenoh's threads, on one of ours
        self._control_thread = threading.Thread(target=self._serve_controls, name="faultmas-inspect-control",
                                                daemon=True)
        self._control_thread.start()
        if self.bridge is not None:
            self.bridge.on_message = self._on_message
            self.bridge.on_membership = self._on_membership  # agents made and killed at run time
        self._thread = threading.Thread(target=self._stream, name="faultmas-inspect-stream", daemon=True)
        self._thread.start()
        return self

    def watch(self, agent: Any) -> None:
        """Serve ``agent``'s mind (a launched agent at ``start``, a made one when it is made)."""
        session, name = self.transport.session, agent.name
        watched = _Watched(agent, PauseGate(agent, self._stopping), self.history)
        watched.stream = session.declare_publisher(keys.stream_key(self.mas, name))
        listener = watched.stream.declare_matching_listener(
            lambda status, w=watched: self._on_matching(w, status.matching))
        queryable = session.declare_queryable(keys.state_key(self.mas, name),
                                              lambda query, w=watched: self._on_state_query(w, query))
        # each agent's own key: every process of the MAS has a publisher, only the agent's answers
        control = session.declare_queryable(keys.control_key(self.mas, name),
                                            lambda query, n=name: self._controls.put((n, query)))
        watched.declared = [listener, queryable, control, watched.stream]
        self.agents[name] = watched

    def unwatch(self, name: str) -> None:
        """``name`` was killed: its mind is no longer served (a paused one is let go)."""
        watched = self.agents.pop(name, None)
        if watched is not None:
            watched.gate.resume()
            _undeclare(watched.declared)

    def _on_membership(self, name: str, agent: Any) -> None:
        if agent is not None:
            self.watch(agent)
        else:
            self.unwatch(name)

    def close(self) -> None:
        """Undeclare everything and let paused agents go (the process is stopping)."""
        self._closed.set()
        self._wake.set()
        self._controls.put(None)
        for watched in list(self.agents.values()):
            watched.gate.resume()
        if self.bridge is not None and getattr(self.bridge, "on_message", None) == self._on_message:
            self.bridge.on_message = None
        if self.bridge is not None and getattr(self.bridge, "on_membership", None) == self._on_membership:
            self.bridge.on_membership = None
        for watched in list(self.agents.values()):
            _undeclare(watched.declared)
            watched.declared = []
        if self._thread is not None:
            self._thread.join(2.0)

    def _stopping(self) -> bool:
        # LocalRuntime.stop() sets _stop_at (a signal, .stopMAS, the launcher): a paused agent lets go
        return self._closed.is_set() or getattr(self.runtime, "_stop_at", None) is not None

    # -- what the page reads ---------------------------------------------------------------------
    def mind(self, name: str, plans: bool = False) -> dict:
        watched = self.agents[name]
        state = snapshot.mind(watched.agent, paused=watched.gate.paused, control=self.allow_control,
                              plans=plans, messages=self._messages(watched),
                              diagnoses=list(getattr(watched.agent, "diagnosis_calls", ())))
        state["observers"] = observers_of(watched.agent)
        return state

    def _on_state_query(self, watched: _Watched, query: Any) -> None:
        try:
            parameters = str(query.parameters)
            if "summary" in parameters:
                state = snapshot.summary(watched.agent, watched.gate.paused)
            else:
                state = self.mind(watched.agent.name, plans="plans" in parameters)
            query.reply(keys.state_key(self.mas, watched.agent.name), self._sealed(watched.agent.name, _encode(state)))
        except Exception as exc:  # never kill Zenoh's thread; the viewer gets a reason
            log.exception("inspector: state of %s could not be read", watched.agent.name)
            query.reply_err(json.dumps({"error": str(exc)}))

    # -- messages (called by the TransportBridge: the agents' and the network threads) -----------
    def _on_message(self, direction: str, agent: str, message: Any) -> None:
        watched = self.agents.get(agent)
        if watched is not None:
            watched.messages.append((time.time(), direction, message))

    @staticmethod
    def _messages(watched: _Watched) -> list[dict]:
        out = []
        for when, direction, m in list(watched.messages):
            if direction == "in":   # an Envelope: content is already text
                peer, content = m.sender, m.content
            else:                   # a Message: its content is a term
                peer, content = m.receiver, to_str(m.content)
            out.append({"t": when, "dir": direction, "peer": peer, "performative": m.performative,
                        "content": content[:500]})
        return out

    # -- the change stream -----------------------------------------------------------------------
    def _on_matching(self, watched: _Watched, matching: bool) -> None:
        watched.watchers = matching
        watched.last_put = None
        if matching:
            self._wake.set()

    def _stream(self) -> None:
        """Put the mind of every watched agent that has cycled since its last put; sleep while
        nobody watches (woken by a matching listener)."""
        while not self._closed.is_set():
            watched_now = [w for w in list(self.agents.values()) if w.watchers]  # (agents come and go)
            if not watched_now:
                self._wake.wait()
                self._wake.clear()
                continue
            for watched in watched_now:
                mark = (watched.agent.cycles, watched.gate.paused, len(watched.messages))
                if mark == watched.last_put:
                    continue
                try:
                    watched.stream.put(self._sealed(watched.agent.name, _encode(self.mind(watched.agent.name))))
                    watched.last_put = mark
                except Exception:  # a failed read or put must not end the stream
                    log.exception("inspector: could not stream the mind of %s", watched.agent.name)
            self._closed.wait(self.period)

    # -- pause / step / resume -------------------------------------------------------------------
    def _serve_controls(self) -> None:
        while True:
            item = self._controls.get()
            if item is None:
                return
            name, query = item
            try:
                request = self._request(name, query)
                answer = self._control(name, request) if request is not None else \
                    {"ok": False, "error": "refused: not signed by a key of the project"}
                query.reply(keys.control_key(self.mas, name), self._sealed(name, _encode(answer)))
            except Exception:  # a viewer gone meanwhile: nothing to answer
                log.exception("inspector: a control request for %s failed", name)
            finally:
                query.drop()

    def _sealed(self, name: str, document: bytes) -> bytes:
        """What agent ``name`` answers or streams: signed by it in the secure profile."""
        identity = self.transport.identity
        return identity.seal(name, document) if identity is not None and identity.can_sign(name) else document

    def _request(self, name: str, query: Any) -> dict | None:
        """A control request; in the secure profile only one signed by a key of the project (its ``by``), else
        None (refused, the drop logged by the transport)."""
        identity = self.transport.identity
        if identity is None:
            return _payload(query)
        from agents.transport.envelope import BadMessage

        payload = query.payload.to_bytes() if query.payload is not None else b""
        where = keys.control_key(self.mas, name)
        try:
            request = identity.open_control(payload)
        except BadMessage as bad:
            self.transport.report_refused(bad.reason, where, bad.sender, bad.detail)
            return None
        except (ValueError, RecursionError) as exc:    # signed, but no JSON object
            self.transport.report_refused("bad_control", where, None, str(exc)[:80])
            return None
        return request

    def _control(self, name: str, request: dict) -> dict:
        watched = self.agents.get(name)
        command = request.get("command")
        if watched is None:
            return {"ok": False, "error": f"no agent {name!r} in this process"}
        if command not in COMMANDS:
            return {"ok": False, "error": f"unknown command {command!r}; expected one of {', '.join(COMMANDS)}"}
        if not self.allow_control:
            return {"ok": False, "error": "this MAS does not allow pausing its agents (start it with --allow-pause)"}
        gate = watched.gate
        ok = True
        if command == "pause":
            ok = gate.pause()
        elif command == "step":
            if not gate.paused:
                return {"ok": False, "error": "pause the agent before stepping it", "cycles": watched.agent.cycles}
            ok = gate.step()
        else:
            gate.resume()
        log.info("inspector: %s %s (cycle %d)", command, name, watched.agent.cycles)
        return {"ok": ok, "command": command, "paused": gate.paused, "cycles": watched.agent.cycles,
                **({} if ok else {"error": f"agent {name} did not reach its next cycle in time"})}


def _payload(query: Any) -> dict:
    payload = query.payload
    if payload is None:
        return {}
    try:
        data = json.loads(payload.to_bytes() or b"{}")
    except ValueError:
        return {}
    return data if isinstance(data, dict) else {}


def _undeclare(entities: list[Any]) -> None:
    for entity in reversed(entities):
        try:
            entity.undeclare()
        except Exception:  # the session may be gone already
            pass


def _encode(state: dict) -> bytes:
    return json.dumps(state, separators=(",", ":"), default=str).encode()
