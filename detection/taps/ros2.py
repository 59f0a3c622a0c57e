"""The live ROS 2 tap: raw subscriptions, the node graph and psutil samples, on one reader thread.

Messages are taken raw by a ``TopicReader`` (``ros2_reader``: no deserialization unless an observer
reads a field) and stamped with the time the middleware received them; the same thread advances the
observers' clock (so silence is noticed), polls the graph for ``activated`` and samples processes for
``resource``, so messages reach the observers in receive-time order. A topic without a configured
``msg_type`` is subscribed to as soon as the graph shows it.
"""
from __future__ import annotations

import importlib
import logging
import time
from typing import Callable

from detection.config import ObserverConfig
from detection.observation import Observation
from detection.observer_set import ObserverSet
from detection.taps import codec
from detection.taps.live import LiveTap
from detection.taps.ros2_reader import Batch, TopicReader
from detection.taps.ros2_take import HEAD_BYTES

log = logging.getLogger("faultmas.detection")
GRAPH_PERIOD = 0.1          # seconds between graph polls (activated reacts within this + one evaluation)


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
        period = 0.5 / max(config.rate_hz, 1.0)        # two ticks per evaluation period
        # messages are taken once per tick, all at once (each keeps its receive time, so the observers
        # see the same stream): one wake-up per tick instead of one per message
        self.reader = TopicReader(self.ros.context, batch_s=period, name="faultmas_observers")
        self._listener = self.reader.add_listener(self._on_batch, topics=(), on_tick=self._tick, tick_s=period)
        self.node = self.reader.node
        self._failed: set[str] = set()
        self._last_graph = 0.0

    def start(self) -> "Ros2Tap":
        self.begin()
        for topic, msgtype in self.config.topics.items():
            if msgtype:
                self._subscribe(topic, msgtype)
        self.reader.start()
        return self

    def close(self) -> None:
        self.reader.close()
        self.ros.close()
        self.close_recorder()


    def _subscribe(self, topic: str, msgtype: str) -> None:
        cls = message_class(msgtype)
        if topic in self.config.decoded:
            try:
                self._decoders[topic] = codec.decoder(msgtype)
            except codec.UnknownType as exc:
                raise TapError(f"{topic}: {exc}") from None
        self.types[topic] = msgtype
        self.reader.listen_to(self._listener, topic)
        # without a recording or a decoder, an observer reads at most a message's header (its stamp):
        # a camera's pixels need not be copied
        whole = self.recorder is not None or topic in self._decoders
        self.reader.subscribe(topic, cls, head=None if whole else HEAD_BYTES)
        log.info("observing %s (%s)", topic, msgtype)

    # -- on the reader's thread ----------------------------------------------------------------------
    def _on_batch(self, batch: Batch) -> None:
        decoders, types, feed = self._decoders, self.types, self.feed
        for t_ns, topic, raw in batch:
            feed(topic, raw=raw, decode=decoders.get(topic), msgtype=types[topic], t_ns=t_ns)

    def _tick(self) -> None:
        wall = time.monotonic()
        if wall - self._last_graph >= GRAPH_PERIOD:
            self._last_graph = wall
            self._poll_graph()
        self.tick()

    def _poll_graph(self) -> None:
        if self.config.nodes:
            self.graph(frozenset(f"{ns.rstrip('/')}/{name}" for name, ns in self.node.get_node_names_and_namespaces()))
        pending = [t for t in self.config.topics if t not in self.types and t not in self._failed]
        if pending:
            present = dict(self.node.get_topic_names_and_types())
            for topic in pending:
                types = present.get(topic)
                if types:
                    try:
                        self._subscribe(topic, types[0])
                    except TapError as exc:
                        log.error("%s", exc)
                        self._failed.add(topic)             # reported once, not retried


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
