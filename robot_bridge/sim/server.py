"""``SimServer``: the robots of one simulated ``World`` served over Zenoh to agents in other processes.

Each robot is a ``SimBridge`` in this process; agents reach it through ``robot_bridge.zenoh_bridge``
(keys and wire format are documented there). Percept snapshots go out when they change (checked every
``interval`` seconds of wall time) and at least every ``refresh`` seconds, and always just before an
action's status, so an agent that sees ``move`` completed also perceives where the robot ended up. The
world's simulated time goes out every ``interval`` (the clock key: the agents' waits follow it, see
``robot_bridge.clock``).
A malformed request is answered with ``bad_args`` when it has an id, else dropped with a log line.

In the secure profile (``sealed``: an ``agents.transport.sealed.SealedChannel`` holding the environment's
private key) the server signs what it sends as the environment and takes a robot's action requests only when
signed by the agent that drives it (its namesake); others are dropped with the transport's rate-limited log
line and never reach the robot.
"""
from __future__ import annotations

import logging
import threading
import time
from typing import Any

from robot_bridge.failure_log import FailureLog
from robot_bridge.protocol import Action, Completion
from robot_bridge.sim.bridge import SimBridge
from robot_bridge.zenoh_bridge import clock_document, clock_key, robot_key

log = logging.getLogger(__name__)

SNAPSHOT_TTL_S = 2.0
"""Percepts an agent received vanish this long after the last snapshot (a dead server goes blind)."""


class SimServer:
    """Serves ``bridges`` (robot name -> set-up ``SimBridge``) on ``session`` under MAS ``mas``."""

    def __init__(self, session: Any, mas: str, bridges: dict[str, SimBridge], interval: float = 0.02,
                 refresh: float = 0.25, sealed: Any = None) -> None:
        self.session, self.mas, self.bridges = session, mas, dict(bridges)
        self.sealed = sealed
        if sealed is not None and not sealed.can_sign(sealed.environment):
            raise ValueError("the secure profile's simulator server needs the environment's private key")
        self.interval, self.refresh = interval, refresh
        self._declared: list = []
        self._publishers: dict[str, tuple[Any, Any]] = {}
        self._last: dict[str, tuple[str, float]] = {}
        self._locks = {name: threading.Lock() for name in self.bridges}
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.requests = 0
        self._clock_publisher: Any = None

    def start(self) -> "SimServer":
        self._clock_publisher = self.session.declare_publisher(clock_key(self.mas))
        self._declared.append(self._clock_publisher)
        self.publish_clock()
        for name in self.bridges:
            status = self.session.declare_publisher(robot_key(self.mas, name, "status"))
            percepts = self.session.declare_publisher(robot_key(self.mas, name, "percepts"))
            self._publishers[name] = (status, percepts)
            sub = self.session.declare_subscriber(robot_key(self.mas, name, "actions"),
                                                  lambda sample, n=name: self._on_request(n, sample))
            self._declared += [status, percepts, sub]
            self.publish_percepts(name, force=True)
        self._thread = threading.Thread(target=self._loop, name="sim-server", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2.0)
        for declared in self._declared:
            try:
                declared.undeclare()
            except Exception:
                pass
        self._declared = []

    def publish_percepts(self, name: str, force: bool = False) -> None:
        """Send robot ``name``'s percepts if they changed (or ``force``, or the refresh is due)."""
        from robot_bridge.ros2 import wire

        # signed, a snapshot names its robot: put on another robot's key, it is refused there (not one of its own)
        text = wire.PerceptSnapshot(name if self.sealed is not None else "", "sim", tuple(self.bridges[name].percepts()),
                                    SNAPSHOT_TTL_S).to_json()
        now = time.monotonic()
        with self._locks[name]:
            last_text, last_time = self._last.get(name, ("", 0.0))
            if not force and text == last_text and now - last_time < self.refresh:
                return
            self._last[name] = (text, now)
            self._publishers[name][1].put(self._sealed(text.encode()))

    def publish_clock(self) -> None:
        """Send the world's simulated time (every ``interval``, changed or not: the ticks also say the server
        is there, so a paused world's time stands while a dead server's runs on, see ``robot_bridge.clock``)."""
        if self.bridges:
            seconds = next(iter(self.bridges.values())).world.time
            self._clock_publisher.put(repr(seconds) if self.sealed is None else self._sealed(clock_document(seconds)))

    def _sealed(self, document: bytes) -> bytes:
        """``document`` as sent: signed by the environment in the secure profile."""
        return document if self.sealed is None else self.sealed.seal(self.sealed.environment, document)

    def _loop(self) -> None:
        """Every ``interval``: the clock, then each robot's percepts; what fails is logged (once, then at 10,
        100... in a row: not a line every 20 ms) and tried again next time (a closed session at shutdown is
        not logged)."""
        publishers = [(FailureLog(log, "sim server: publishing the clock"), self.publish_clock)]
        publishers += [(FailureLog(log, f"sim server: publishing {name}'s percepts"),
                        lambda name=name: self.publish_percepts(name)) for name in self.bridges]
        while not self._stop.wait(self.interval):
            for failures, publish in publishers:
                try:
                    publish()
                except Exception as exc:
                    if not self._stop.is_set():
                        failures.failed(exc)
                else:
                    failures.succeeded()

    def _on_request(self, name: str, sample) -> None:
        from robot_bridge.ros2 import wire

        payload = sample.payload.to_bytes()
        if self.sealed is not None:   # only the robot's own agent may move it
            payload = self.sealed.open(payload, name, str(sample.key_expr))
            if payload is None:
                return   # refused (logged and counted by the sealed channel), not a request served
        self.requests += 1
        try:
            request = wire.ActionRequest.from_json(payload.decode())
            action = Action(request.action_name, request.values(), id=request.id)
        except (wire.WireError, UnicodeDecodeError, ValueError) as exc:
            log.warning("sim server: dropped a bad action request for %s: %s", name, exc)
            return
        future = self.bridges[name].act(action)
        future.add_done_callback(lambda f: self._answer(name, action, f))

    def _answer(self, name: str, action: Action, future) -> None:
        from robot_bridge.ros2 import wire
        try:
            completion = future.result()
        except Exception as exc:
            completion = Completion.failure("bridge_error", str(exc))
        try:
            self.publish_percepts(name, force=True)
            self._publishers[name][0].put(self._sealed(wire.ActionStatus(
                name, action.id, completion.ok, completion.reason, completion.detail).to_json().encode()))
        except Exception as exc:  # the server is closing: the agents are gone too
            if not self._stop.is_set():
                log.warning("sim server: cannot answer %s of %s: %s", action, name, exc)
