"""``ZenohBridge``: a robot served over Eclipse Zenoh, e.g. the embedded simulator in another process.

The wire format is jason_ros's (``robot_bridge.ros2.wire``), so one format serves ROS 2 topics and Zenoh
keys alike. Per robot, under the MAS namespace:

==========================================  =================================================
key                                         payload
==========================================  =================================================
``faultmas/<mas>/robot/<robot>/actions``    agent -> robot: ``ActionRequest`` (with an id)
``faultmas/<mas>/robot/<robot>/status``     robot -> agent: ``ActionStatus`` once the motion finished
``faultmas/<mas>/robot/<robot>/percepts``   robot -> agent: ``PerceptSnapshot`` (source, ttl)
``faultmas/<mas>/clock``                    robot -> agents: the robots' time, seconds as a decimal
                                            number (a simulator's ``/clock``; optional)
==========================================  =================================================

The server side for the simulator is ``robot_bridge.sim.server.SimServer``. A robot that stops answering
fails its pending actions with ``timeout``; its percepts expire after their ``ttl``. The bridge's clock
(``clock()``, which the agent's waits follow, and its actions' time bounds) follows the clock key while it
ticks and runs at wall pace while it does not (``robot_bridge.clock``): a server without a clock is wall time.

Options: ``mas`` (namespace, default ``faultmas``), ``session`` (an open ``zenoh.Session`` to share,
e.g. the agent's own transport session) or ``connect`` (endpoints; a private loopback peer session is
opened), ``action_timeout`` (seconds; default: from the action's own time bound). The agent's process sets
``sealed`` (no option: an ``agents.transport.sealed.SealedChannel``) before ``setup`` in the secure profile.

In the secure profile (docs/reliability.md, "Identity") every message on these keys is signed: percepts,
action results and the clock by the environment (the process that serves the robots, whose public key the
project lists), an action request by the agent that drives the robot (its namesake). An outsider on the network
could otherwise put percepts that steer the agent's beliefs, answer its actions, or move its robot. What is
unsigned, signed by another key or replayed is dropped with the transport's rate-limited log line; the clock is
then the JSON object ``{"time": SECONDS}`` (a seal needs an object).
"""
from __future__ import annotations

import logging
import threading
import time
from concurrent.futures import Future
from typing import Any, ClassVar

from robot_bridge import actions
from robot_bridge.clock import FollowingClock
from robot_bridge.failure_log import FailureLog
from robot_bridge.messaging import PendingActions, PerceptStore, answer_timeout
from robot_bridge.protocol import Action, Completion, Percept, RobotBridge, completed

log = logging.getLogger(__name__)

EXPIRE_INTERVAL_S = 0.05
CLOCK_SILENCE_S = 5.0
"""Wall seconds without a clock tick (sent every 20 ms) after which the server counts as gone; the clock
then runs on at wall pace after ``robot_bridge.clock.STALE_S`` more."""


def robot_key(mas: str, robot: str, channel: str) -> str:
    """The key expression of ``channel`` (``actions``, ``status`` or ``percepts``) of one robot."""
    return f"faultmas/{mas}/robot/{robot}/{channel}"


def clock_key(mas: str) -> str:
    """The key expression on which a MAS's robot server publishes the robots' time (seconds)."""
    return f"faultmas/{mas}/clock"


def clock_document(seconds: float) -> bytes:
    """The clock's payload in the secure profile, before its seal: ``{"time":SECONDS}``."""
    return b'{"time":%s}' % repr(float(seconds)).encode()


def clock_seconds(text: str) -> float:
    """The seconds in a secure-profile clock document (``ValueError`` when it is not one)."""
    import json

    data = json.loads(text)
    seconds = data.get("time") if isinstance(data, dict) else None
    if isinstance(seconds, bool) or not isinstance(seconds, (int, float)):
        raise ValueError('expected {"time": SECONDS}')
    return float(seconds)


class ZenohBridge(RobotBridge):
    """Drives one robot whose server (simulator or driver) listens on Zenoh."""

    name: ClassVar[str] = "zenoh"

    def __init__(self, robot: str, mas: str = "faultmas", session: Any = None, connect: Any = (),
                 action_timeout: float | None = None, **options: object) -> None:
        super().__init__(robot, **options)
        self.mas = mas
        self.sealed: Any = None
        """The secure profile (set by the agent's process before ``setup``): signs actions, checks the rest."""
        self._session, self._owns_session = session, session is None
        self.connect = (connect,) if isinstance(connect, str) else tuple(connect)
        self.action_timeout = action_timeout
        self._server_time: float | None = None
        self._clock_heard = -float("inf")       # wall time of the last tick (the server sends one per 20 ms)
        self._clock = FollowingClock(lambda: self._server_time, alive=self._server_ticks)
        self._pending = PendingActions(self._clock)
        self._store = PerceptStore(robot)
        self._declared: list = []
        self._stop = threading.Event()
        self._expirer: threading.Thread | None = None
        self._ready = False

    def setup(self, timeout: float = 5.0) -> None:
        """Subscribe and wait until the robot's server has sent its first percepts."""
        if self._session is None:
            import zenoh

            from agents.transport.config import ZenohOptions, build_config
            self._session = zenoh.open(build_config(ZenohOptions(connect=self.connect)))
        session = self._session
        self._publisher = session.declare_publisher(robot_key(self.mas, self.robot, "actions"))
        self._declared = [
            self._publisher,
            # one subscriber for status and percepts: zenoh-python runs each subscriber's callbacks on a
            # thread of its own, and the server's last snapshot must be stored before the status it precedes
            # (an agent that sees ``move`` completed perceives where the robot ended up)
            session.declare_subscriber(robot_key(self.mas, self.robot, "*"), self._on_robot),
            session.declare_subscriber(clock_key(self.mas), self._on_clock),
        ]
        self._expirer = threading.Thread(target=self._expire_loop, name=f"zenoh-bridge-{self.robot}", daemon=True)
        self._expirer.start()
        self._ready = True
        if not self._store.received.wait(timeout):
            where = robot_key(self.mas, self.robot, "percepts")
            self.shutdown()
            signed = " percepts signed by the environment's key" if self.sealed is not None else ""
            raise TimeoutError(f"no robot server publishes{signed} on {where} after {timeout:g} s "
                               f"(is the simulator running for MAS {self.mas!r}?)")

    def act(self, action: Action) -> "Future[Completion]":
        from robot_bridge.ros2 import wire

        if not self._ready:
            return completed(Completion.failure("shutdown", "the bridge is not set up"))
        failure = actions.check(action)
        if failure is not None:
            return completed(failure)
        limit = float(self.action_timeout) if self.action_timeout else answer_timeout(action)
        future = self._pending.add(action, limit)
        request = wire.ActionRequest(self.robot, action.name, tuple(wire.format_value(a) for a in action.args),
                                     action.id)
        payload = request.to_json().encode()
        if self.sealed is not None:
            payload = self.sealed.seal(self.robot, payload)
        self._publisher.put(payload)
        return future

    def percepts(self) -> list[Percept]:
        return self._store.percepts()

    def clock(self) -> float:
        """The server's time while it publishes one (a simulator's), else wall pace (``robot_bridge.clock``)."""
        return self._clock()

    def shutdown(self) -> None:
        self._ready = False
        self._stop.set()
        self._pending.fail_all("shutdown")
        for declared in self._declared:
            try:
                declared.undeclare()
            except Exception:  # the session may already be closed
                pass
        self._declared = []
        if self._owns_session and self._session is not None:
            self._session.close()
            self._session = None

    # -- network threads: never raise -----------------------------------------------------------
    def _opened(self, sample) -> bytes | None:
        """The payload of ``sample``; in the secure profile only if the environment signed it (else None: the
        drop is logged and counted by the agent's transport)."""
        payload = sample.payload.to_bytes()
        if self.sealed is None:
            return payload
        return self.sealed.open(payload, self.sealed.environment, str(sample.key_expr))

    def _on_robot(self, sample) -> None:
        """A sample of this robot's keys, in the order the server sent them (its own ``actions`` ignored)."""
        channel = str(sample.key_expr).rpartition("/")[2]
        if channel == "status":
            self._on_status(sample)
        elif channel == "percepts":
            self._on_percepts(sample)

    def _on_status(self, sample) -> None:
        from robot_bridge.ros2 import wire
        payload = self._opened(sample)
        if payload is None:
            return
        try:
            status = wire.ActionStatus.from_json(payload.decode())
        except (wire.WireError, UnicodeDecodeError) as exc:
            log.warning("%s: dropped a bad status message: %s", self.robot, exc)
            return
        if status.agent_name in ("", self.robot):
            self._pending.finish(status.id, Completion.success() if status.result
                                 else Completion.failure(status.reason or "failed", status.detail))

    def _on_percepts(self, sample) -> None:
        from robot_bridge.ros2 import wire
        payload = self._opened(sample)
        if payload is None:
            return
        try:
            text = payload.decode()
            if self.sealed is not None and wire.decode_percepts(text).agent_name != self.robot:
                # the environment's signature, but another robot's percepts (put on this robot's key)
                self.sealed.refuse("replayed", str(sample.key_expr), self.sealed.environment,
                                   "percepts of another robot")
                return
            self._store.receive(text)
        except (wire.WireError, UnicodeDecodeError) as exc:
            log.warning("%s: dropped a bad percept message: %s", self.robot, exc)

    def _on_clock(self, sample) -> None:
        payload = self._opened(sample)
        if payload is None:
            return
        text = ""
        try:
            text = payload.decode()
            seconds = float(clock_seconds(text) if self.sealed is not None else text)
            if seconds != seconds or seconds in (float("inf"), float("-inf")):
                raise ValueError("not a finite number")
        except (UnicodeDecodeError, ValueError) as exc:
            log.warning("%s: dropped a bad clock message %.40r (expected seconds as a number): %s", self.robot, text, exc)
            return
        self._server_time = seconds
        self._clock_heard = time.monotonic()

    def _server_ticks(self) -> bool:
        """Whether the server's clock ticks arrive (a paused world's time stands; a dead server's does not)."""
        return time.monotonic() - self._clock_heard < CLOCK_SILENCE_S

    def _expire_loop(self) -> None:
        failures = FailureLog(log, f"Zenoh bridge of {self.robot}: expiring unanswered actions")  # never hang one
        while not self._stop.wait(EXPIRE_INTERVAL_S):
            with failures.contained():
                self._pending.expire(f"robot {self.robot} (key {robot_key(self.mas, self.robot, 'status')})")
