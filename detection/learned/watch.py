"""The learned ``resource`` observer on a live ROS 2 graph: discover the components, find their
processes, tap their channels, tick once a second, hand observations to a pipeline.

The architecture model the diagnoser needs comes from the same discovery (``architecture_yaml``):
every component is a node with the topics it publishes and subscribes, and declares ``resource(C)``.
"""
from __future__ import annotations

import re
from typing import Callable, Iterable, Sequence

from detection.learned.encoding import RosEncoder
from detection.learned.features import feature_names
from detection.learned.model import ComponentModel, ModelFileError
from detection.learned.observer import (COMPONENTS_CHANNEL, TICK_CHANNEL, LearnedResourceObserver, model_channels,
                                       model_columns, node_processes, tick_record)
from detection.learned.ros_tap import Component, RawTap, discover
from detection.learned.zenoh_events import (AGENT_NODE, ZenohFeed, adopt_bridge_nodes, agent_component,
                                            agent_processes, is_zenoh_channel, mas_of, wait_for_bridge_nodes)

AGENT_SUFFIX = "_" + AGENT_NODE
from detection.observation import Observation


def topic_atom(topic: str) -> str:
    """``/faulty/commands/velocity`` → ``faulty_commands_velocity`` (an architecture model's topic name)."""
    return re.sub(r"[^A-Za-z0-9_]", "_", topic.strip("/")).lower()


def architecture_yaml(name: str, components: Iterable[Component]) -> str:
    """An architecture model (``diagnosis.architecture_yaml``) of the discovered components, declaring
    ``resource(C)`` for each. Topics that no watched component publishes are left out (the format wants
    a publisher for every subscribed topic)."""
    components = sorted(components, key=lambda c: c.name)
    published = {topic_atom(t) for c in components for t in c.outputs}
    lines = [f"architecture: {name}", "nodes:"]
    for c in components:
        pub = sorted({topic_atom(t) for t in c.outputs})
        sub = sorted({topic_atom(t) for t in c.inputs} & published)
        lines.append(f"  {c.name}: {{pub: [{', '.join(pub)}], sub: [{', '.join(sub)}]}}")
    lines.append("observations:")
    lines += [f"  - resource({c.name})" for c in components]
    return "\n".join(lines) + "\n"


class LiveLearnedObserver:
    """Runs a ``LearnedResourceObserver`` on a ROS 2 domain (and on Zenoh for agents' models) until ``close()``.

    The ROS 2 components come from the graph under ``namespaces``; an agent's component (a model whose
    channels include Zenoh keys, ``zenoh_events``) is its ROS 2 bridge node under its name, plus the
    keys its model was trained on, tapped on a Zenoh session of ours connected to ``zenoh_connect``
    (loopback endpoints; never multicast). Zenoh's samples are queued and taken in the ROS 2 reader's
    thread at each tick, so the buffers are only ever touched by one thread."""

    def __init__(self, models: dict[str, ComponentModel], namespaces: list[str], emit: Callable[[list[Observation]], object],
                 domain_id: int | None = None, confirm: tuple[int, int] = (3, 5), settle_s: float = 2.0,
                 skip_unfit: bool = False, zenoh_connect: Sequence[str] = (), agents_timeout_s: float = 30.0,
                 discovery_s: float = 20.0, *, reader=None, zenoh_keys=None,
                 record: Callable[..., None] | None = None) -> None:
        """``skip_unfit``: watch only the components whose model fits the live system (the others are
        listed in ``unfit``) instead of refusing with a ``ModelFileError``. ``agents_timeout_s``: how
        long to wait for the ROS 2 bridge nodes of the agents the models watch (agents start slowly).
        ``discovery_s``: how long discovery may take to show every model's component with all its
        topics (DDS discovery of a busy graph takes seconds); a model still missing or unfit then is
        refused (or, with ``skip_unfit``, left out).

        Sharing, so that each message is received once per process (``faultmas observe CONFIG --learned``):
        ``reader``, a started or not yet started ``TopicReader`` of the observers' tap, takes the models'
        topics too (its context and node are used; no participant of ours); ``zenoh_keys``, the Zenoh
        tap's ``ZenohKeys``, carries the agents' keys. ``record(channel, t_ns, raw=, data=, msgtype=)``
        (a ``LiveTap.record``) gets every message tapped and, at each tick, the counters read
        (``@learned``), so that ``replay_ticks`` over the bag gives the same verdicts."""
        import time

        import rclpy

        from robot_bridge.ros2.runtime import RosContext

        zenoh_columns = {c: {t: cols for t, cols in model_columns(m).items() if is_zenoh_channel(t)}
                         for c, m in models.items()}
        agents = [c[:-len(AGENT_SUFFIX)] for c, cols in zenoh_columns.items() if cols and c.endswith(AGENT_SUFFIX)]
        self.zenoh: ZenohFeed | None = None
        self.tap: RawTap | None = None
        self.record = record
        self.ros = RosContext(domain_id=domain_id).start() if reader is None else None
        try:
            node = reader.node if reader is not None else \
                self.ros.add(rclpy.create_node("faultmas_learned_resource", context=self.ros.context))
            time.sleep(settle_s)                                     # discovery has no fixed delay
            wait_for_bridge_nodes(node, agents, agents_timeout_s)    # missing ones: their models are unfit
            deadline = time.monotonic() + discovery_s
            while True:            # until every model's component is seen with all its topics, or the deadline
                components, topic_types = discover(node, namespaces, ignore_nodes=[node.get_name()])
                self.components = adopt_bridge_nodes(components, agents)
                for agent in agents:               # an agent whose bridge node is not (yet) in the graph
                    self.components.setdefault(agent_component(agent), Component(agent_component(agent), "", agent))
                missing = sorted(set(models) - set(self.components))
                columns = {t: RosEncoder.for_type(ty).columns for t, ty in topic_types.items()}
                self.unfit = {c: reason for c, m in models.items() if c in self.components
                              and (reason := self._unfit(c, m, self.components[c], {**columns, **zenoh_columns[c]}))}
                if (not missing and not self.unfit) or time.monotonic() > deadline:
                    break
                time.sleep(0.5)
            if missing:
                raise ModelFileError(f"models for components not running here: {', '.join(missing)}")
            if self.unfit and not skip_unfit:
                raise ModelFileError("; ".join(self.unfit.values()))
            models = {c: m for c, m in models.items() if c not in self.unfit}
            agent_names = {agent_component(a): a for a in agents}
            nodes = [self.components[c] for c in models if c not in agent_names]
            processes = node_processes(nodes, domain_id) if nodes else {}
            for c, agent in agent_names.items():   # by MAS too: another MAS on this host may have an agent of that name
                if c in models:
                    processes.update(agent_processes([agent], mas_of(zenoh_columns[c]), zenoh_connect))
            self.observer = LearnedResourceObserver(models, processes, emit, confirm)
            if record is not None:
                record(COMPONENTS_CHANNEL, time.time_ns(), data={c: self.components[c].to_dict() for c in models})
            keys = {t: cols for c in models for t, cols in zenoh_columns[c].items()}
            if keys:
                self.zenoh = ZenohFeed(keys, self.observer.on_event, connect=zenoh_connect, keys=zenoh_keys)
            self.types = {t: ty for t, ty in topic_types.items() if t in self.observer.buffers}
            on_raw = None if record is None else \
                (lambda t_ns, topic, raw: record(topic, t_ns, raw=raw, msgtype=self.types[topic]))
            self.tap = RawTap(node, self.types, self.observer.on_event, on_tick=self._tick, reader=reader,
                              on_raw=on_raw)                       # the reader's thread: no race
        except BaseException:
            self.close()
            raise

    def _tick(self) -> None:
        if self.zenoh is not None:
            self.zenoh.drain()
        self.observer.tick()
        if self.record is not None and self.observer.last_tick is not None:
            self.record(TICK_CHANNEL, int(self.observer.last_tick * 1e9), data=tick_record(self.observer))

    @staticmethod
    def _unfit(name: str, model: ComponentModel, component: Component, columns: dict[str, list[str]]) -> str:
        """Why ``model`` cannot watch ``component`` as it runs now ('' when it can). A Zenoh key's
        columns are the model's own (``columns`` has them): JSON values have no type to compare."""
        channels = sorted(set(component.channels) | {t for t in columns if is_zenoh_channel(t)})
        live = [n for topic in channels for n in feature_names(topic, columns.get(topic, []))]
        if live == model.features:
            return ""
        trained = {topic for topic, _ in model_channels(model)}
        return (f"model of {name!r} does not fit the live system (channels now: {len(channels)}, "
                f"in training: {len(trained)}; new: {sorted(set(channels) - trained)[:3]}, "
                f"gone: {sorted(trained - set(channels))[:3]}, or other message types); train it again")

    def close(self) -> None:
        if self.tap is not None:
            self.tap.close()
        if self.zenoh is not None:
            self.zenoh.close()
        if self.ros is not None:
            self.ros.close()
