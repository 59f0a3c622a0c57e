"""The live ROS 2 tap: raw rclpy subscriptions, the node graph and psutil samples, on one executor thread.

Messages are taken raw (``raw=True``: no deserialization unless an observer reads a field) and stamped
with the receive time in the callback; a timer advances the observers' clock (so silence is noticed),
polls the graph for ``activated`` and samples processes for ``resource``. Everything runs on one
SingleThreadedExecutor, so messages reach the observers in receive-time order. A topic without a
configured ``msg_type`` is subscribed to as soon as the graph shows it.
"""
from __future__ import annotations

import importlib
import logging
import time
from typing import Callable

from detection.config import ObserverConfig
from detection.message import Message
from detection.observation import Observation
from detection.observer_set import ObserverSet
from detection.observers.activated import GRAPH_CHANNEL
from detection.observers.resource import RESOURCE_CHANNEL
from detection.taps import codec
from detection.taps.processes import ProcessSampler

log = logging.getLogger("faultmas.detection")
GRAPH_PERIOD = 0.1          # seconds between graph polls (activated reacts within this + one evaluation)
RESOURCE_PERIOD = 0.5       # seconds between psutil samples


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


class Ros2Tap:
    """Feeds ``observers`` from a live ROS 2 graph; ``on_observations`` gets what changed."""

    def __init__(self, config: ObserverConfig, observers: ObserverSet,
                 on_observations: Callable[[list[Observation]], None], *, domain_id: int | None = None,
                 recorder=None, clock: Callable[[], int] = time.time_ns) -> None:
        from robot_bridge.ros2.runtime import RosContext

        self.config = config
        self.observers = observers
        self.on_observations = on_observations
        self.recorder = recorder
        self.clock = clock
        self.types: dict[str, str] = {}
        self._decoders: dict[str, Callable] = {}
        for topic, msgtype in config.topics.items():     # fail before touching the network
            if msgtype:
                message_class(msgtype)
        self.ros = RosContext(domain_id=domain_id)
        import rclpy.node

        self.node = self.ros.add(rclpy.node.Node("faultmas_observers", context=self.ros.context))
        self._subscriptions: dict[str, object] = {}
        self._graph: frozenset[str] | None = None
        self._last_graph = self._last_resource = 0.0
        self._sampler = ProcessSampler(config.processes) if config.processes else None
        self._started = False

    # -- running ------------------------------------------------------------------------------------
    def start(self) -> "Ros2Tap":
        t0 = self.clock()
        self.observers.start(t0)
        if self.recorder is not None:
            self.recorder.start(t0)
        for topic, msgtype in self.config.topics.items():
            if msgtype:
                self._subscribe(topic, msgtype)
        self.node.create_timer(1.0 / max(self.config.rate_hz, 1.0) / 2, self._tick)
        self.ros.start()
        self._started = True
        return self

    def close(self) -> None:
        self.ros.close()
        if self.recorder is not None:
            self.recorder.close()
            self.recorder = None

    def _subscribe(self, topic: str, msgtype: str) -> None:
        from rclpy.qos import qos_profile_sensor_data

        cls = message_class(msgtype)
        if topic in self.config.decoded:
            try:
                self._decoders[topic] = codec.decoder(msgtype)
            except codec.UnknownType as exc:
                raise TapError(f"{topic}: {exc}") from None
        self.types[topic] = msgtype
        self._subscriptions[topic] = self.node.create_subscription(
            cls, topic, lambda raw, t=topic: self._on_raw(t, raw), qos_profile_sensor_data, raw=True)
        log.info("observing %s (%s)", topic, msgtype)

    # -- callbacks (executor thread) ----------------------------------------------------------------
    def _on_raw(self, topic: str, raw: bytes) -> None:
        msg = Message(topic, self.clock(), raw=raw, decode=self._decoders.get(topic))
        self._feed(msg, self.types[topic])

    def _feed(self, msg: Message, msgtype: str | None = None) -> None:
        if self.recorder is not None:
            self.recorder.write(msg, msgtype)
        changed = self.observers.feed(msg)
        if changed:
            self.on_observations(changed)

    def _tick(self) -> None:
        now = self.clock()
        wall = time.monotonic()
        if wall - self._last_graph >= GRAPH_PERIOD:
            self._last_graph = wall
            self._poll_graph(now)
        if self._sampler is not None and wall - self._last_resource >= RESOURCE_PERIOD:
            self._last_resource = wall
            for node, sample in self._sampler.sample().items():
                self._feed(Message(RESOURCE_CHANNEL + node, now, sample))
        changed = self.observers.advance(now)
        if changed:
            self.on_observations(changed)

    def _poll_graph(self, now: int) -> None:
        if self.config.nodes:
            names = frozenset(f"{ns.rstrip('/')}/{name}" for name, ns in self.node.get_node_names_and_namespaces())
            if names != self._graph:
                self._graph = names
                self._feed(Message(GRAPH_CHANNEL, now, names))
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
