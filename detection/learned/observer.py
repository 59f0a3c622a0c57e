"""The learned ``resource`` observer: the trained models watching the live system, once a second.

Beside the running nodes it taps every channel of the watched components (``ros_tap``), samples
each component's process (``counters``), computes the same features as in training
(``features.ChannelBuffer``) and scores each component's model. A component whose distance is above
its threshold in ``confirm[0]`` of the last ``confirm[1]`` ticks becomes ``resource(C) = false``
(the paper's ``~resource(C)``); it turns true again once that no longer holds. One flagged second is
not enough on purpose: at a 0.5 % target FPR and a handful of components, single-tick verdicts would
raise a false alarm every minute or so. As every observer does (docs/observers.md), it emits an
``Observation`` (source ``learned``, ``measured`` = the squared distance) when the verdict is first
known and each time it flips, for ``Pipeline.observe``.
"""
from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from detection.learned.counters import TARGET_NAMES, read_counters, targets_from_counters
from detection.learned.features import ChannelBuffer
from detection.learned.model import ComponentModel, ModelFileError
from detection.learned.record import event_times
from detection.observation import Observation

DEFAULT_CONFIRM = (3, 5)


SOURCE = "learned"


def model_channels(model: ComponentModel) -> list[tuple[str, int]]:
    """The channels a model reads, in its feature order, with their event widths."""
    order: dict[str, int] = {}
    for name in model.features:
        topic, window, *column = name.split("|")
        if window == "last":
            order[topic] = order.get(topic, 0) + 1
        else:
            order.setdefault(topic, 0)
    return list(order.items())


def model_columns(model: ComponentModel) -> dict[str, list[str]]:
    """The event columns of each channel a model reads (from its ``channel|last|column`` features)."""
    columns: dict[str, list[str]] = {}
    for name in model.features:
        topic, window, *column = name.split("|")
        if window == "last":
            columns.setdefault(topic, []).append(column[0])
        else:
            columns.setdefault(topic, [])
    return columns


class LearnedResourceObserver:
    """Scores every watched component at each tick; hands the observations that changed to ``emit``
    (e.g. ``Pipeline.observe``)."""

    def __init__(self, models: dict[str, ComponentModel], processes: dict[str, object],
                 emit: Callable[[list[Observation]], object], confirm: tuple[int, int] = DEFAULT_CONFIRM) -> None:
        missing = sorted(set(models) - set(processes))
        if missing:
            raise ValueError(f"no process found for {', '.join(missing)}")
        self.models, self.processes, self.emit, self.confirm = models, processes, emit, confirm
        self.channels = {c: model_channels(m) for c, m in models.items()}
        widths = {topic: width for chans in self.channels.values() for topic, width in chans}
        self.buffers = {topic: ChannelBuffer(width) for topic, width in widths.items()}
        self.previous: dict[str, np.ndarray] = {}
        self.recent = {c: deque(maxlen=confirm[1]) for c in models}
        self.ok: dict[str, bool | None] = {c: None for c in models}        # None: not known yet
        self.last_distance: dict[str, float] = {}
        self.tick_seconds: list[float] = []
        self.tick_cpu_seconds: list[float] = []
        self.last_tick: float | None = None
        self.last_samples: dict[str, np.ndarray | None] = {}

    def on_event(self, t: float, topic: str, vector: np.ndarray) -> None:
        buffer = self.buffers.get(topic)
        if buffer is not None:
            buffer.add(t, vector)

    def features(self, component: str, tick: float) -> np.ndarray:
        return np.concatenate([self.buffers[topic].features(tick) for topic, _ in self.channels[component]])

    def tick(self, now: float | None = None, counters: dict[str, np.ndarray] | None = None) -> list[Observation]:
        """Score every component at ``now``; returns (and emits) the observations that changed.

        ``counters`` (component → ``COUNTER_NAMES`` sample) replaces reading the processes: a recorded
        run replayed through this very code (``replay``)."""
        now = time.time() if now is None else now
        started, started_cpu = time.perf_counter(), time.thread_time()
        samples = {}
        for c, process in self.processes.items():
            if counters is not None:
                sample = counters.get(c)
                samples[c] = None if sample is None or not np.isfinite(sample).all() else sample
                continue
            try:
                samples[c] = read_counters(process)
            except Exception:                       # a process that is gone: the activated observer's job
                samples[c] = None
        self.last_tick, self.last_samples = now, samples
        features = {topic: buffer.features(now) for topic, buffer in self.buffers.items()}
        changes = []
        for c, model in self.models.items():
            sample, previous = samples[c], self.previous.get(c)
            if sample is not None:
                self.previous[c] = sample
            if sample is None or previous is None:
                continue
            y = targets_from_counters(np.vstack([previous, sample]))[0]
            x = np.concatenate([features[topic] for topic, _ in self.channels[c]])
            distance = float(model.score(x, y)[0])
            self.last_distance[c] = distance
            self.recent[c].append(distance > model.threshold)
            ok = sum(self.recent[c]) < self.confirm[0]
            if ok != self.ok[c]:
                self.ok[c] = ok
                changes.append(Observation(f"resource({c})", ok, now, measured=distance, source=SOURCE))
        self.tick_seconds.append(time.perf_counter() - started)
        self.tick_cpu_seconds.append(time.thread_time() - started_cpu)     # what a busy machine does not inflate
        if changes:
            self.emit(changes)
        return changes


TICK_CHANNEL = "@learned"
"""The tap channel on which a recording keeps each tick's time and counters (``faultmas observe --learned
--record``): with the topics' messages, what ``BagReplay`` needs to give the live verdicts again."""


COMPONENTS_CHANNEL = "@learned/components"
"""Where a recording keeps the watched components (``ros_tap.Component.to_dict``), as discovered live:
a replay diagnoses with the architecture the live run had."""


def tick_record(observer: LearnedResourceObserver) -> dict:
    """The last tick as JSON: its time and each component's counters (None: its process was not read)."""
    return {"t": observer.last_tick,
            "counters": {c: None if s is None else [float(v) for v in s] for c, s in observer.last_samples.items()}}


class BagReplay:
    """The learned observer over a recorded bag (``faultmas observe --bag PATH --learned MODELS_DIR``):
    the models' topics encoded as live, a tick at each recorded ``@learned`` tick with its recorded
    counters. ``feed(msg)`` takes the bag's messages in order and returns the observations that changed.
    A message tapped live just after a tick's last batch but received before it is replayed before that
    tick: the verdicts are the live ones up to such messages in flight at a tick."""

    def __init__(self, models: dict[str, ComponentModel], topic_types: dict[str, str],
                 confirm: tuple[int, int] = DEFAULT_CONFIRM) -> None:
        from detection.learned.encoding import RosEncoder
        from detection.learned.zenoh_events import is_zenoh_channel

        zenoh = sorted(c for c, m in models.items() if any(is_zenoh_channel(t) for t in model_columns(m)))
        if zenoh:
            raise ModelFileError(f"models of {', '.join(zenoh)} read Zenoh keys, which a rosbag does not hold; "
                                 "leave them out of MODELS_DIR to replay the others")
        self.observer = LearnedResourceObserver(models, {c: None for c in models}, lambda _obs: None, confirm)
        self.topics = set(self.observer.buffers)
        self.channels = {TICK_CHANNEL, COMPONENTS_CHANNEL}
        # a topic the bag lacks had no message in the run (its counts stay 0, as live)
        self.encoders = {t: RosEncoder.for_type(topic_types[t]) for t in self.topics if t in topic_types}
        self.dropped: dict[str, int] = {}
        self.ticks = 0

    def feed(self, msg) -> list[Observation]:
        if msg.channel == COMPONENTS_CHANNEL:
            return []
        if msg.channel == TICK_CHANNEL:
            self.ticks += 1
            counters = {c: None if v is None else np.array(v, dtype=np.float64)
                        for c, v in msg.data["counters"].items()}
            return self.observer.tick(float(msg.data["t"]), counters)
        try:
            vector = self.encoders[msg.channel].encode_raw(msg.raw)
        except Exception:                       # counted as live, never raised
            self.dropped[msg.channel] = self.dropped.get(msg.channel, 0) + 1
            return []
        self.observer.on_event(msg.t_ns / 1e9, msg.channel, vector)
        return []


def replay(observer: LearnedResourceObserver, run_file: str | Path,
           on_tick: Callable[[float], None] | None = None) -> list[Observation]:
    """Feed a recorded run (``record``'s file) through ``observer`` in time order, ticking at the
    recorded ticks with the recorded counters; returns every observation emitted. ``on_tick(t)`` is
    called after each tick (``observer.last_distance`` then holds that tick's distances)."""
    with np.load(run_file) as data:
        arrays = {key: data[key] for key in data.files}
    events = []
    for topic in observer.buffers:
        times = event_times(arrays, topic)
        if times is not None:
            values = arrays[f"events/{topic}/x"].astype(np.float64)
            events += [(t, topic, v) for t, v in zip(times, values)]
    events.sort(key=lambda e: e[0])
    emitted: list[Observation] = []
    i = 0
    for k, tick in enumerate(arrays["ticks"]):
        while i < len(events) and events[i][0] <= tick:
            observer.on_event(*events[i])
            i += 1
        counters = {c: arrays[f"counters/{c}"][k] for c in observer.models if f"counters/{c}" in arrays}
        emitted += observer.tick(float(tick), counters)
        if on_tick is not None:
            on_tick(float(tick))
    return emitted


def load_models(directory: str | Path, components: Iterable[str] | None = None) -> dict[str, ComponentModel]:
    """Every ``<component>.npz`` model in ``directory`` (only those of ``components`` when given)."""
    directory = Path(directory)
    paths = sorted(directory.glob("*.npz"))
    if not paths:
        raise ModelFileError(f"{directory}: no model files (*.npz); save them with "
                             "'faultmas experiment perfbugs --save-models DIR'")
    wanted = None if components is None else set(components)
    models = {}
    for path in paths:
        if wanted is None or path.stem in wanted:
            model = ComponentModel.load(path, component=path.stem, targets=list(TARGET_NAMES))
            models[model.component] = model
    return models


def node_processes(components, domain_id: int | None = None) -> dict[str, object]:
    """The process of each ROS component (``ros_tap.Component``), found by its command line
    (``-m robot_bridge.ros2.<node> --robot <robot>``, as ``robot_bridge.ros2.launch`` starts them) and,
    with ``domain_id``, its ROS domain (``--domain-id N`` or ``ROS_DOMAIN_ID`` in its environment): two
    teams on one host have the same command lines otherwise. Raises ``ValueError`` when a component
    matches several processes (another team in the same domain) rather than watch the wrong one."""
    import psutil

    def in_domain(process, cmdline: list[str]) -> bool:
        if domain_id is None:
            return True
        if "--domain-id" in cmdline:
            i = cmdline.index("--domain-id")
            return i + 1 < len(cmdline) and cmdline[i + 1] == str(domain_id)
        try:
            return process.environ().get("ROS_DOMAIN_ID", "0") == str(domain_id)
        except psutil.Error:
            return False

    found: dict[str, list] = {}
    for process in psutil.process_iter(["cmdline"]):
        cmdline = process.info.get("cmdline") or []
        for c in components:
            robot = c.namespace.strip("/")
            if f"robot_bridge.ros2.{c.node}" in cmdline and (not robot or robot in cmdline) \
                    and in_domain(process, cmdline):
                found.setdefault(c.name, []).append(process)
    ambiguous = {name: [p.pid for p in ps] for name, ps in found.items() if len(ps) > 1}
    if ambiguous:
        raise ValueError(f"several processes look like the same node (pids {ambiguous}); give the ROS domain id")
    return {name: ps[0] for name, ps in found.items()}
