"""The viewer side: one Zenoh session gathers what the page shows of a MAS, from any of its hosts.

* the team: liveliness tokens (``faultmas/<mas>/alive/*``: an agent that dies is gone in milliseconds,
  a frozen host within the link lease) and, twice a second, every agent's summary (one query);
* the mind of each agent someone looks at: one full query, then its change stream while looked at
  (the agent publishes it only while this subscriber exists);
* the robots: their percept snapshots (odometry pose, camera detections) and, when the simulator runs
  in this process, its ground truth (``truth``);
* the timeline: the agents' ``.progress`` steps on the MAS's control key (what ``faultmas run`` prints), the
  newest ``timeline_marks`` of them (a team held up for days must not grow the viewer without bound): marks are
  numbered from the first the hub saw, so a reader that asks for the marks from number N on (``view``) gets the
  same ones whatever was dropped before; the view says how many earlier marks were dropped.

In the secure profile (``transport`` given, with an identity: ``faultmas run --secure --inspect``) the team
and the timeline come from the transport, which checks signatures: an agent is listed alive only while its
token is up and its signed heartbeats come (``agents.transport.proved_presence``: an outsider's token makes
nobody alive), and the timeline shows only ``.progress`` reports signed by the agent they name (an outsider
cannot write into it; the refused ones are counted in ``refused_marks`` and logged by the transport). The
minds and summaries shown are only those signed by their agent (an outsider's answer on an agent's key is
dropped by the transport's drop log), and pause/step/resume go out signed by this process's key of the project
(the run's own hub: the environment's; ``faultmas inspect --identity``): without one they are not sent.

A message that does not decode is dropped with one warning line naming its key; the hub goes on.
Readers (the web app) wait on ``changed`` and read ``view()``; everything else happens on Zenoh's
threads and the hub's poller.
"""
from __future__ import annotations

import collections
import itertools
import json
import logging
import math
import threading
import time
from typing import Any, Callable

from agents.inspector import TIMELINE_MARKS, keys
from agents.transport import keys as mas_keys
from robot_bridge.failure_log import FailureLog

log = logging.getLogger("faultmas.inspector")

POLL = 0.2            # seconds between ground-truth samples
SUMMARY_EVERY = 0.5   # seconds between two summary queries of the team
QUERY_TIMEOUT = 2.0
TRAIL_POINTS = 600    # points kept per trail (older ones thinned)
TRAIL_STEP = 0.01     # metres a robot moves before its trail gets a point


def _every_reply():
    """Every reply of a query, unconsolidated: an outsider's reply on an agent's key must not displace the agent's
    (Zenoh keeps one reply per key by default; the secure profile then drops the outsider's and keeps the agent's)."""
    import zenoh

    return zenoh.ConsolidationMode.NONE


class _Trail:
    """A robot's path, thinned to ``TRAIL_POINTS`` by dropping every other old point."""

    def __init__(self) -> None:
        self.points: list[tuple[float, float]] = []

    def add(self, x: float, y: float) -> None:
        if self.points and math.hypot(x - self.points[-1][0], y - self.points[-1][1]) < TRAIL_STEP:
            return
        self.points.append((round(x, 3), round(y, 3)))
        if len(self.points) > TRAIL_POINTS:
            self.points = self.points[: TRAIL_POINTS // 2: 2] + self.points[TRAIL_POINTS // 2:]


class TeamHub:
    """What the page shows of MAS ``mas``, kept up to date from ``session`` (an open Zenoh session).

    ``clock()``: the time the timeline is stamped with (the simulator's; default: wall seconds since
    the hub started); ``truth()``: robot name -> (x m, y m, yaw degrees) ground truth, if known."""

    def __init__(self, session: Any, mas: str, *, clock: Callable[[], float] | None = None,
                 truth: Callable[[], dict[str, tuple[float, float, float]]] | None = None,
                 transport: Any = None, timeline_marks: int = TIMELINE_MARKS) -> None:
        if timeline_marks < 1:
            raise ValueError(f"timeline_marks must be at least 1, not {timeline_marks}")
        self.session = session
        self.transport = transport if transport is not None and transport.identity is not None else None
        self._sealed = self.transport.sealed_channel() if self.transport is not None else None
        self.mas = mas_keys.check_name(mas, "MAS name")
        self.started = time.monotonic()
        self.clock = clock or (lambda: time.monotonic() - self.started)
        self.clock_name = "simulated" if clock is not None else "wall"
        self.truth = truth
        self.changed = threading.Condition()
        self.version = 0
        self.agents: dict[str, dict] = {}        # name -> {"alive", "changed_at", "summary"}
        self.minds: dict[str, dict] = {}         # name -> latest full state (with "plans" once)
        self.robots: dict[str, dict] = {}        # name -> {"odom", "trail", "seen", "truth", "truth_trail"}
        self._timeline: collections.deque[dict] = collections.deque(maxlen=timeline_marks)   # the newest marks
        self.timeline_dropped = 0                # marks older than ``timeline``'s first, no longer kept
        self.dropped = 0
        self.refused_marks = 0                   # the secure profile: reports not signed by their agent
        self._trails: dict[tuple[str, str], _Trail] = {}
        self._watch: dict[str, tuple[int, Any]] = {}   # agent -> (viewers, subscriber)
        self._fetching: set[str] = set()                # agents whose plan library is being asked for
        self._lock = threading.RLock()
        self._declared: list[Any] = []
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # -- life cycle ------------------------------------------------------------------------------
    def start(self) -> "TeamHub":
        s = self.session
        self._declared = [s.declare_subscriber(keys.robot_percepts_pattern(self.mas), self._on_percepts)]
        if self.transport is None:
            self._declared += [
                s.liveliness().declare_subscriber(mas_keys.alive_pattern(self.mas), self._on_alive, history=True),
                s.declare_subscriber(mas_keys.control_key(self.mas), self._on_control)]
        else:   # signatures checked by the transport (the secure profile)
            self.transport.on_presence(self._on_presence)
            self.transport.on_control(self._on_proved_control)
        self._thread = threading.Thread(target=self._poll, name="faultmas-inspect-hub", daemon=True)
        self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()
        with self._lock:
            subscribers = [sub for _, sub in self._watch.values()]
            self._watch.clear()
        for entity in [*subscribers, *self._declared]:
            try:
                entity.undeclare()
            except Exception:  # the session may be closed already
                pass
        if self._thread is not None:
            self._thread.join(2.0)
        self._bump()

    def _bump(self) -> None:
        with self.changed:
            self.version += 1
            self.changed.notify_all()

    def _drop(self, key: str, reason: str) -> None:
        log.warning("inspector: dropped a malformed message on %s: %s", key, reason[:120])
        self.dropped += 1

    # -- the team --------------------------------------------------------------------------------
    def _on_alive(self, sample: Any) -> None:
        import zenoh

        self._on_presence(mas_keys.last_chunk(str(sample.key_expr)), sample.kind == zenoh.SampleKind.PUT)

    def _on_presence(self, name: str, alive: bool) -> None:
        if self._stop.is_set():
            return
        with self._lock:
            entry = self.agents.setdefault(name, {"alive": alive, "summary": None})
            entry["alive"], entry["changed_at"] = alive, time.time()
        self._bump()

    def _poll(self) -> None:
        next_summary = 0.0
        summaries = FailureLog(log, "inspector hub: the agents' summaries")   # one bad round, not the viewer's feed
        while not self._stop.wait(POLL):
            if self.truth is not None:
                try:
                    self._sample_truth()
                except Exception:  # a world being torn down: next time
                    log.debug("ground truth not available", exc_info=True)
            if time.monotonic() >= next_summary:
                next_summary = time.monotonic() + SUMMARY_EVERY
                with summaries.contained():
                    self._query_summaries()

    def _query_summaries(self) -> None:
        try:
            replies = list(self.session.get(keys.state_pattern(self.mas) + "?summary", timeout=QUERY_TIMEOUT,
                                            consolidation=_every_reply()))
        except Exception as exc:  # session closing
            log.debug("summary query failed: %s", exc)
            return
        changed = False
        for reply in replies:
            if reply.ok is None:
                continue
            key = str(reply.ok.key_expr)
            state = self._decode(key, reply.ok.payload.to_bytes())
            if state is None:
                continue
            with self._lock:
                entry = self.agents.setdefault(keys.agent_of(key), {"alive": True, "summary": None})
                if entry["summary"] != state:
                    entry["summary"], changed = state, True
        if changed:
            self._bump()

    def _decode(self, key: str, payload: bytes) -> dict | None:
        """A state message, or None (dropped with a log line) when it is not one; in the secure profile only
        one its agent signed."""
        if self.transport is not None:
            payload = self._sealed.open(payload, keys.agent_of(key), key)
            if payload is None:
                return None
        try:
            state = json.loads(payload)
            if not isinstance(state, dict) or not isinstance(state.get("agent"), str) \
                    or not isinstance(state.get("cycles"), int):
                raise ValueError("expected an object with 'agent' and 'cycles'")
            if state["agent"] != keys.agent_of(key):
                raise ValueError(f"state of {state['agent']!r} on the key of another agent")
        except ValueError as exc:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
            self._drop(key, str(exc))
            return None
        return state

    # -- minds -----------------------------------------------------------------------------------
    def watch(self, agent: str) -> None:
        """Someone looks at ``agent``: fetch its whole mind, then follow its change stream."""
        mas_keys.check_name(agent)
        with self._lock:
            viewers, subscriber = self._watch.get(agent, (0, None))
            if subscriber is None:
                subscriber = self.session.declare_subscriber(keys.stream_key(self.mas, agent), self._on_stream)
            self._watch[agent] = (viewers + 1, subscriber)
        if viewers == 0:
            threading.Thread(target=self._refresh_in_background, args=(agent,), daemon=True).start()

    def unwatch(self, agent: str) -> None:
        with self._lock:
            viewers, subscriber = self._watch.get(agent, (0, None))
            if viewers > 1:
                self._watch[agent] = (viewers - 1, subscriber)
                return
            self._watch.pop(agent, None)
        if subscriber is not None:
            subscriber.undeclare()

    def refresh(self, agent: str) -> dict | None:
        """Query ``agent``'s whole mind (with its plan library) now."""
        key = keys.state_key(self.mas, agent)
        for reply in self.session.get(key + "?plans", timeout=QUERY_TIMEOUT, consolidation=_every_reply()):
            if reply.ok is not None:
                state = self._decode(key, reply.ok.payload.to_bytes())
                if state is not None:
                    self._store_mind(state)
                    return state
        return None

    def _on_stream(self, sample: Any) -> None:
        key = str(sample.key_expr)
        state = self._decode(key, sample.payload.to_bytes())
        if state is not None:
            self._store_mind(state)

    def _store_mind(self, state: dict) -> None:
        name = state["agent"]
        fetch_plans = False
        with self._lock:
            old = self.minds.get(name)
            if "plans" not in state:          # the stream leaves the plan library out
                if old is not None and "plans" in old:
                    state["plans"] = old["plans"]
                elif name not in self._fetching:   # watched before it was up: ask for it once
                    self._fetching.add(name)
                    fetch_plans = True
            self.minds[name] = state
            entry = self.agents.setdefault(name, {"alive": True, "summary": None})
            entry["summary"] = {k: state.get(k) for k in
                                ("agent", "cycles", "paused", "robot", "top", "intentions", "beliefs",
                                 "events", "source")}
        self._bump()
        if fetch_plans:
            threading.Thread(target=self._fetch_plans, args=(name,), daemon=True).start()

    def _fetch_plans(self, name: str) -> None:
        try:
            self._refresh_in_background(name)
        finally:
            with self._lock:
                self._fetching.discard(name)

    def _refresh_in_background(self, name: str) -> None:
        """``refresh`` on a thread of its own: a failure is logged, not the thread's end (a zenoh.ZError when the
        session closes under it, seen as a test's end; every such thread goes through here)."""
        try:
            self.refresh(name)
        except Exception as exc:
            if not self._stop.is_set():
                log.warning("inspector: %s's mind could not be fetched: %s", name, exc)

    def control(self, agent: str, command: str) -> dict:
        """Ask ``agent`` to pause, step or resume; its answer (it refuses unless the MAS allows it)."""
        key = keys.control_key(self.mas, agent)
        payload: str | bytes = json.dumps({"command": command})
        if self.transport is not None:   # the secure profile: signed by a key of the project, or not sent
            identity = self.transport.identity
            signer = next(iter(sorted(identity.private_keys)), None)
            if signer is None:
                return {"ok": False, "error": "this inspector holds no key of the project, so the agents would "
                                              "refuse it (faultmas inspect --identity KEY.pem)"}
            payload = identity.seal_control({"command": command, "by": signer})
        for reply in self.session.get(key, payload=payload, timeout=QUERY_TIMEOUT + 6.0,
                                      consolidation=_every_reply()):
            if reply.ok is not None:
                opened = reply.ok.payload.to_bytes()
                if self.transport is not None:
                    opened = self._sealed.open(opened, agent, key)
                    if opened is None:
                        continue
                try:
                    answer = json.loads(opened)
                except ValueError as exc:
                    self._drop(key, str(exc))
                    continue
                threading.Thread(target=self._refresh_in_background, args=(agent,), daemon=True).start()
                return answer
        return {"ok": False, "error": f"agent {agent} did not answer (gone, or not inspectable)"}

    # -- the timeline ----------------------------------------------------------------------------
    def _on_control(self, sample: Any) -> None:
        try:
            message = json.loads(sample.payload.to_bytes())
        except ValueError:
            return   # the transport itself logs bad control messages
        if isinstance(message, dict):
            self._add_mark(message)

    def _on_proved_control(self, message: dict) -> None:
        """The secure profile: a control message opened by the transport (``by`` kept only when its signature
        proved it); a report joins the timeline only if signed by the agent it names."""
        from agents.progress import ProgressReport

        if self._stop.is_set() or ProgressReport.from_message(message) is None:
            return
        if not ProgressReport.proved(message):
            with self._lock:
                self.refused_marks += 1
            return
        self._add_mark(message)

    def _add_mark(self, message: dict) -> None:
        from agents.progress import ProgressReport

        report = ProgressReport.from_message(message)
        if report is None:
            return
        mark = {"agent": report.agent, "step": report.step, "detail": report.detail,
                "t": round(self.clock(), 3), "wall": round(time.monotonic() - self.started, 3)}
        with self._lock:
            if len(self._timeline) == self._timeline.maxlen:
                self.timeline_dropped += 1       # the oldest goes
            self._timeline.append(mark)
        self._bump()

    # -- the world -------------------------------------------------------------------------------
    def _robot(self, name: str) -> dict:
        return self.robots.setdefault(name, {"odom": None, "seen": [], "truth": None, "origin": None})

    def _trail(self, name: str, kind: str) -> _Trail:
        return self._trails.setdefault((name, kind), _Trail())

    def _on_percepts(self, sample: Any) -> None:
        from robot_bridge.ros2.wire import PerceptSnapshot, WireError

        key = str(sample.key_expr)
        try:
            snap = PerceptSnapshot.from_json(sample.payload.to_bytes().decode())
        except (WireError, ValueError) as exc:
            self._drop(key, str(exc))
            return
        name = keys.agent_of(key)
        odom, seen = None, []
        for p in snap.percepts:
            if p.name == "odom" and len(p.args) == 3:
                odom = tuple(float(a) for a in p.args)
            elif p.name == "robot_seen" and len(p.args) == 4:
                seen.append({"robot": str(p.args[0]), "angle_deg": float(p.args[1]),
                             "depth_m": float(p.args[2]), "yaw_deg": float(p.args[3])})
        with self._lock:
            robot = self._robot(name)
            moved = odom is not None and odom != robot["odom"]
            if moved:
                robot["odom"] = odom
                self._trail(name, "odom").add(odom[0], odom[1])
            if seen != robot["seen"]:
                robot["seen"], moved = seen, True
        if moved:
            self._bump()

    def _sample_truth(self) -> None:
        poses = self.truth() if self.truth is not None else {}
        changed = False
        with self._lock:
            for name, (x, y, yaw) in poses.items():
                robot = self._robot(name)
                pose = (round(x, 3), round(y, 3), round(yaw, 1))
                if robot["origin"] is None:   # odometry starts at zero where the robot stood: the map
                    robot["origin"] = pose    # draws it from there, in the world's frame
                if pose != robot["truth"]:
                    robot["truth"], changed = pose, True
                    self._trail(name, "truth").add(x, y)
        if changed:
            self._bump()

    # -- what readers get ------------------------------------------------------------------------
    @property
    def timeline(self) -> list[dict]:
        """The marks kept, oldest first (a copy)."""
        with self._lock:
            return list(self._timeline)

    def view(self, agent: str | None = None, timeline_from: int = 0) -> dict:
        """A JSON-ready picture: the team, the robots, the timeline marks numbered ``timeline_from`` and later
        that are still kept (``timeline_first``: the number of the first one given; ``timeline_length``: how many
        marks there have been, the ``timeline_from`` of the next view; ``timeline_dropped``: how many of the
        oldest are no longer kept), and the mind of ``agent`` if one is watched."""
        with self._lock:
            team = [{**(e.get("summary") or {}), "agent": name, "alive": e["alive"]}
                    for name, e in sorted(self.agents.items())]
            robots = {name: {**r, "trail": list(self._trail(name, "odom").points),
                             "truth_trail": list(self._trail(name, "truth").points)}
                      for name, r in sorted(self.robots.items())}
            return {"mas": self.mas, "clock": self.clock_name, "version": self.version, "team": team,
                    "robots": robots, **self._marks_from(timeline_from),
                    "mind": self.minds.get(agent) if agent else None}

    def _marks_from(self, number: int) -> dict:
        """The kept marks numbered ``number`` and later (under ``_lock``)."""
        first = max(number, self.timeline_dropped)
        marks = list(itertools.islice(self._timeline, first - self.timeline_dropped, None))
        return {"timeline": marks, "timeline_first": first,
                "timeline_length": self.timeline_dropped + len(self._timeline),
                "timeline_dropped": self.timeline_dropped, "timeline_limit": self._timeline.maxlen}
