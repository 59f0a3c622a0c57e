"""The learned ``resource`` observer on a live ROS 2 graph: discover the components, find their
processes, tap their channels, tick once a second, hand observations to a pipeline.

The architecture model the diagnoser needs comes from the same discovery (``architecture_yaml``):
every component is a node with the topics it publishes and subscribes, and declares ``resource(C)``.
"""
from __future__ import annotations

import re
from typing import Callable, Iterable

from detection.learned.encoding import RosEncoder
from detection.learned.features import feature_names
from detection.learned.model import ComponentModel, ModelFileError
from detection.learned.observer import LearnedResourceObserver, model_channels, node_processes
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
                 domain_id: int | None = None, confirm: tuple[int, int] = (3, 5), settle_s: float = 10.0,
                 skip_unfit: bool = False) -> None:
        """``settle_s``: how long discovery may take at most. ``skip_unfit``: watch only the components
        whose model fits the live system (the others are listed in ``unfit``) instead of refusing with a
        ``ModelFileError``."""
        import time

        import rclpy

        from robot_bridge.ros2.runtime import RosContext

        self.tap = None
        self.ros = RosContext(domain_id=domain_id).start()
        try:
            node = self.ros.add(rclpy.create_node("faultmas_learned_resource", context=self.ros.context))
            deadline = time.monotonic() + settle_s          # discovery has no fixed delay (slower on a busy host):
            while True:                                     # look again until every model's component fits
                time.sleep(0.5)
                self.components, topic_types = discover(node, namespaces, ignore_nodes=[node.get_name()])
                missing = sorted(set(models) - set(self.components))
                if not missing:
                    columns = {t: RosEncoder.for_type(ty).columns for t, ty in topic_types.items()}
                    self.unfit = {c: reason for c, m in models.items()
                                  if (reason := self._unfit(c, m, self.components[c], columns))}
                if time.monotonic() >= deadline or not (missing or self.unfit):
                    break
            if missing:
                raise ModelFileError(f"models for components not running here: {', '.join(missing)}")
            if self.unfit and not skip_unfit:
                raise ModelFileError("; ".join(self.unfit.values()))
            models = {c: m for c, m in models.items() if c not in self.unfit}
            processes = node_processes([self.components[c] for c in models], domain_id)
            self.observer = LearnedResourceObserver(models, processes, emit, confirm)
            self.tap = RawTap(node, {t: ty for t, ty in topic_types.items() if t in self.observer.buffers},
                              self.observer.on_event, on_tick=self.observer.tick)   # one thread: no race
        except BaseException:
            self.ros.close()
            raise

    @staticmethod
    def _unfit(name: str, model: ComponentModel, component: Component, columns: dict[str, list[str]]) -> str:
        """Why ``model`` cannot watch ``component`` as it runs now ('' when it can)."""
        live = [n for topic in component.channels for n in feature_names(topic, columns.get(topic, []))]
        if live == model.features:
            return ""
        trained = {topic for topic, _ in model_channels(model)}
        return (f"model of {name!r} does not fit the live system (channels now: {len(component.channels)}, "
                f"in training: {len(trained)}; new: {sorted(set(component.channels) - trained)[:3]}, "
                f"gone: {sorted(trained - set(component.channels))[:3]}, or other message types); train it again")

    def close(self) -> None:
        if self.tap is not None:
            self.tap.close()
        self.ros.close()
