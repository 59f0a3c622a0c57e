"""The learned ``resource`` observer on a live ROS 2 graph: discover the components, find their
processes, tap their channels, tick once a second, hand observations to a pipeline.

The architecture model the diagnoser needs comes from the same discovery (``architecture_yaml``):
every component is a node with the topics it publishes and subscribes, and declares ``resource(C)``.
"""
from __future__ import annotations

import re
from typing import Callable, Iterable

from detection.learned.model import ComponentModel, ModelFileError
from detection.learned.observer import LearnedResourceObserver, node_processes
from detection.learned.ros_tap import Component, RawTap, discover
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
    """Runs a ``LearnedResourceObserver`` on a ROS 2 domain until ``close()``."""

    def __init__(self, models: dict[str, ComponentModel], namespaces: list[str], emit: Callable[[list[Observation]], object],
                 domain_id: int | None = None, confirm: tuple[int, int] = (3, 5), settle_s: float = 2.0) -> None:
        import time

        import rclpy

        from robot_bridge.ros2.runtime import RosContext

        self.ros = RosContext(domain_id=domain_id).start()
        try:
            node = self.ros.add(rclpy.create_node("faultmas_learned_resource", context=self.ros.context))
            time.sleep(settle_s)                                     # discovery has no fixed delay
            self.components, topic_types = discover(node, namespaces, ignore_nodes=[node.get_name()])
            missing = sorted(set(models) - set(self.components))
            if missing:
                raise ModelFileError(f"models for components not running here: {', '.join(missing)}")
            processes = node_processes([self.components[c] for c in models])
            self.observer = LearnedResourceObserver(models, processes, emit, confirm)
            self.tap = RawTap(node, {t: ty for t, ty in topic_types.items()
                                     if t in self.observer.buffers}, self.observer.on_event)
            self._check_columns(models)
            node.create_timer(1.0, lambda: self.observer.tick())     # the executor's thread: no race with the tap
        except BaseException:
            self.ros.close()
            raise

    def _check_columns(self, models: dict[str, ComponentModel]) -> None:
        from detection.learned.features import feature_names
        columns = {t: e.columns for t, e in self.tap.encoders.items()}
        for c, model in models.items():
            live = [n for topic, _ in self.observer.channels[c] for n in feature_names(topic, columns.get(topic, []))]
            if live != model.features:
                raise ModelFileError(f"model of {c!r} does not fit the live system: its channels or their "
                                     "message types differ from the training data; train it again")

    def close(self) -> None:
        self.ros.close()
