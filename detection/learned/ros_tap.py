"""The live ROS 2 side of the learned detector: which component uses which topic, and every message
on those topics as (time, channel, encoded vector), read through the one ROS 2 reader
(``detection.taps.ros2_reader``).

The components and their channels come from the ROS graph itself (publishers and subscriptions per
topic), so no per-system table is written by hand. Only topics inside the watched namespaces are
taken (``/rosout`` and ``/parameter_events`` are every node's housekeeping, not its work).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Callable, Iterable

import numpy as np

from detection.learned.encoding import RosEncoder
from robot_bridge.ros2.perfbugs import component_name

log = logging.getLogger("faultmas.detection")


@dataclass
class Component:
    """One node of the watched system: its name (``robot_node``) and the topics it reads and writes."""

    name: str
    namespace: str
    node: str
    inputs: list[str] = field(default_factory=list)
    outputs: list[str] = field(default_factory=list)

    @property
    def channels(self) -> list[str]:
        return sorted(set(self.inputs) | set(self.outputs))

    def to_dict(self) -> dict:
        return {"namespace": self.namespace, "node": self.node, "inputs": self.inputs, "outputs": self.outputs}


def discover(node, namespaces: Iterable[str], ignore_nodes: Iterable[str] = ()) -> tuple[dict[str, Component], dict[str, str]]:
    """Components in ``namespaces`` (e.g. ``['/faulty', '/helper']``) and the types of their topics."""
    prefixes = tuple(ns.rstrip("/") + "/" for ns in namespaces)
    ignored = set(ignore_nodes)
    components: dict[str, Component] = {}
    types: dict[str, str] = {}

    def component(info) -> Component | None:
        ns = info.node_namespace
        if info.node_name in ignored or not (ns + "/").startswith(prefixes):
            return None
        name = component_name(ns.strip("/").replace("/", "_"), info.node_name)
        return components.setdefault(name, Component(name, ns, info.node_name))

    for topic, topic_types in node.get_topic_names_and_types():
        if not topic.startswith(prefixes):
            continue
        types[topic] = topic_types[0]
        for info in node.get_publishers_info_by_topic(topic):
            if (c := component(info)) is not None and topic not in c.outputs:
                c.outputs.append(topic)
        for info in node.get_subscriptions_info_by_topic(topic):
            if (c := component(info)) is not None and topic not in c.inputs:
                c.inputs.append(topic)
    used = {t for c in components.values() for t in c.channels}
    return components, {t: ty for t, ty in types.items() if t in used}


BATCH_S = 0.1
"""Messages are taken ten times a second (at most 10 of a 100-deep queue: a 1 kHz topic loses none)."""


class RawTap:
    """Every message on ``topics`` encoded and handed to ``on_event(t, topic, vector)``, read by the
    one ROS 2 reader (``detection.taps.ros2_reader.TopicReader``): its own, on a node of its own in
    ``node``'s context, or ``reader`` shared with other consumers (the observers of ``faultmas observe
    CONFIG --learned``: one subscription per topic, so Fast DDS receives each message once).
    ``on_tick()`` (if given) runs every ``tick_s`` seconds on the same thread, so a user needs no lock
    between events and ticks; ``on_raw(t_ns, topic, cdr)`` (if given) sees each message before it is
    encoded (a recording). ``close()`` stops it (closing the context does too). Without ``on_raw``, only
    the first bytes of a big message are copied when they hold all its numbers (``RosEncoder.head_bytes``:
    an image's header and sizes, not its pixels).

    A message that cannot be decoded is counted in ``dropped`` (per topic), never raised in the reader.
    """

    def __init__(self, node, topic_types: dict[str, str], on_event: Callable[[float, str, np.ndarray], None],
                 on_tick: Callable[[], None] | None = None, tick_s: float = 1.0, *, reader=None,
                 on_raw: Callable[[int, str, bytes], None] | None = None) -> None:
        from detection.taps.ros2_reader import TopicReader

        self.encoders = {topic: RosEncoder.for_type(type_name) for topic, type_name in topic_types.items()}
        self.dropped: dict[str, int] = {}
        self.received = 0
        self._on_event, self._on_raw = on_event, on_raw          # before the first message can arrive
        self._owns = reader is None
        self.reader = reader if reader is not None else TopicReader(node.context, batch_s=BATCH_S,
                                                                    name=f"{node.get_name()}_tap")
        self._listener = self.reader.add_listener(self._on_batch, topics=set(self.encoders), on_tick=on_tick,
                                                  tick_s=tick_s, batch_s=BATCH_S)
        for topic, encoder in self.encoders.items():         # a recording keeps whole messages
            self.reader.subscribe(topic, encoder.msg_class, head=None if on_raw is not None else encoder.head_bytes)
        if self._owns:
            self.reader.start()

    def close(self) -> None:
        if self._owns:
            self.reader.close()
        else:
            self.reader.remove_listener(self._listener)

    def _on_batch(self, batch) -> None:
        encoders, on_event, on_raw = self.encoders, self._on_event, self._on_raw
        for t_ns, topic, data in batch:
            if on_raw is not None:
                on_raw(t_ns, topic, data)
            try:
                vector = encoders[topic].encode_raw(data)
            except Exception as exc:            # a bad message is counted and logged, never kills the tap
                self.dropped[topic] = self.dropped.get(topic, 0) + 1
                if self.dropped[topic] == 1 or self.dropped[topic] % 1000 == 0:
                    log.warning("learned tap: %d message(s) on %s could not be encoded (%s)",
                                self.dropped[topic], topic, exc)
                continue
            self.received += 1
            on_event(t_ns / 1e9, topic, vector)
