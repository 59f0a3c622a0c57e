"""The live ROS 2 tap: raw rclpy subscriptions, the node graph and psutil samples, on one executor thread.

Messages are taken raw (no deserialization unless an observer reads a field) and stamped with the
receive time when taken; the same thread advances the observers' clock (so silence is noticed), polls
the graph for ``activated`` and samples processes for ``resource``, so messages reach the observers in
receive-time order. A topic without a configured ``msg_type`` is subscribed to as soon as the graph
shows it.

The thread waits on the subscriptions itself (an rcl wait set, drained completely on each wake-up)
instead of spinning rclpy's Python executor, whose per-message bookkeeping costs ~15x what the
observers do with a message (``python -m benchmarks observers``).
"""
from __future__ import annotations

import importlib
import logging
import threading
import time
from typing import Callable

from detection.config import ObserverConfig
from detection.observation import Observation
from detection.observer_set import ObserverSet
from detection.taps import codec
from detection.taps.live import LiveTap

log = logging.getLogger("faultmas.detection")
GRAPH_PERIOD = 0.1          # seconds between graph polls (activated reacts within this + one evaluation)
BATCH = 0.01                # after a wake-up, let messages gather this long: one wake-up per batch, not
                            # per message (each keeps the time the middleware received it)


class TapError(ValueError):
    """A configuration the live tap cannot serve (e.g. an unknown message type)."""


def message_class(msgtype: str):
    """``sensor_msgs/msg/Imu`` -> the rclpy class; ``TapError`` when no installed package has it."""
    parts = msgtype.split("/")
    if len(parts) == 2:
        parts = [parts[0], "msg", parts[1]]
    try:
        return getattr(importlib.import_module(f"{parts[0]}.{parts[1]}"), parts[2])
    except (ImportError, AttributeError, IndexError):
        raise TapError(f"unknown topic type {msgtype!r}: no installed ROS 2 package defines it") from None


class Ros2Tap(LiveTap):
    """Feeds ``observers`` from a live ROS 2 graph; ``on_observations`` gets what changed."""

    def __init__(self, config: ObserverConfig, observers: ObserverSet,
                 on_observations: Callable[[list[Observation]], None], *, domain_id: int | None = None,
                 recorder=None, clock: Callable[[], int] = time.time_ns) -> None:
        for msgtype in config.topics.values():         # fail before touching the network
            if msgtype:
                message_class(msgtype)
        super().__init__(config, observers, on_observations, recorder=recorder, clock=clock)
        from robot_bridge.ros2.runtime import RosContext

        self.types: dict[str, str] = {}
        self._decoders: dict[str, Callable] = {}
        self.ros = RosContext(domain_id=domain_id)
        import rclpy.node
        from rclpy.guard_condition import GuardCondition

        # not added to the context's executor: this tap's thread takes the messages (see above)
        self.node = rclpy.node.Node("faultmas_observers", context=self.ros.context, start_parameter_services=False)
        self._subscriptions: dict[str, object] = {}
        self._last_graph = 0.0
        self._stop = threading.Event()
        self._wake = GuardCondition(None, None, context=self.ros.context)
        self._thread: threading.Thread | None = None

    def start(self) -> "Ros2Tap":
        self.begin()
        for topic, msgtype in self.config.topics.items():
            if msgtype:
                self._subscribe(topic, msgtype)
        self._thread = threading.Thread(target=self._loop, daemon=True, name="faultmas-ros2-tap")
        self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._wake.trigger()
            self._thread.join(5.0)
        self.node.destroy_node()
        self.ros.close()
        self.close_recorder()

    def _subscribe(self, topic: str, msgtype: str) -> None:
        from rclpy.qos import qos_profile_sensor_data

        cls = message_class(msgtype)
        if topic in self.config.decoded:
            try:
                self._decoders[topic] = codec.decoder(msgtype)
            except codec.UnknownType as exc:
                raise TapError(f"{topic}: {exc}") from None
        self.types[topic] = msgtype
        decode = self._decoders.get(topic)
        self._subscriptions[topic] = self.node.create_subscription(
            cls, topic, lambda _raw: None, qos_profile_sensor_data, raw=True)   # taken by _loop, not a callback
        log.info("observing %s (%s)", topic, msgtype)

    # -- the tap's thread ----------------------------------------------------------------------------
    def _loop(self) -> None:
        from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

        context = self.ros.context
        period_ns = int(0.5e9 / max(self.config.rate_hz, 1.0))
        wait_set, subs = None, []
        next_tick = time.monotonic()
        while not self._stop.is_set() and context.ok():
            current = [(t, s) for t, s in self._subscriptions.items() if s is not None]
            if wait_set is None or len(current) != len(subs):
                subs = current
                with context.handle:
                    wait_set = _rclpy.WaitSet(len(subs), 1, 0, 0, 0, 0, context.handle)
            wait_set.clear_entities()
            for _topic, sub in subs:
                wait_set.add_subscription(sub.handle)
            wait_set.add_guard_condition(self._wake.handle)
            wait_set.wait(max(0, int((next_tick - time.monotonic()) * 1e9)))
            ready = set(wait_set.get_ready_entities("subscription"))
            taken = []
            for topic, sub in subs:
                if sub.handle.pointer in ready:
                    taken.extend(self._drain(topic, sub))
            taken.sort(key=lambda m: m[0])
            for t_ns, topic, raw in taken:
                self.feed(topic, raw=raw, decode=self._decoders.get(topic), msgtype=self.types[topic], t_ns=t_ns)
            if taken:
                self._stop.wait(BATCH)
            if time.monotonic() >= next_tick:
                next_tick = time.monotonic() + period_ns / 1e9
                self._tick()

    @staticmethod
    def _drain(topic: str, sub) -> list[tuple[int, str, bytes]]:
        """Every message waiting on ``sub`` with the time the middleware received it."""
        out = []
        with sub.handle:
            while True:
                taken = sub.handle.take_message(sub.msg_type, True)
                if taken is None:
                    return out
                out.append((taken[1].get("received_timestamp") or time.time_ns(), topic, taken[0]))

    def _tick(self) -> None:
        wall = time.monotonic()
        if wall - self._last_graph >= GRAPH_PERIOD:
            self._last_graph = wall
            self._poll_graph()
        self.tick()

    def _poll_graph(self) -> None:
        if self.config.nodes:
            self.graph(frozenset(f"{ns.rstrip('/')}/{name}" for name, ns in self.node.get_node_names_and_namespaces()))
        pending = [t for t in self.config.topics if t not in self._subscriptions]
        if pending:
            present = dict(self.node.get_topic_names_and_types())
            for topic in pending:
                types = present.get(topic)
                if types:
                    try:
                        self._subscribe(topic, types[0])
                    except TapError as exc:
                        log.error("%s", exc)
                        self._subscriptions[topic] = None      # reported once, not retried


INFO_TOPIC = "/observers/info"


def info_publisher(tap: Ros2Tap, topic: str = INFO_TOPIC):
    """A pipeline listener publishing each ``Update`` as JSON in a ``std_msgs/String`` on ``topic``."""
    import json

    from rclpy.qos import QoSDurabilityPolicy, QoSProfile
    from std_msgs.msg import String

    qos = QoSProfile(depth=100, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL)   # late joiners get the state
    pub = tap.node.create_publisher(String, topic, qos)

    def publish(update) -> None:
        pub.publish(String(data=json.dumps(update.to_json())))
    return publish
