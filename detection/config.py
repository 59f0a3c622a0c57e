"""Observer configuration in YAML, close to tug_observers' layout (docs/observers.md has one example per kind).

```yaml
main_loop_rate: 10          # evaluations per second (default 10)
start_up_time: 1.0          # seconds before the first verdict (default 1; per observer or entry too)
setup:
  - type: hz
    topics:
      - name: /scan
        filter: {type: median, window_size: 10}
        states:
          - state: nominal
            number: 1
            frequency: {type: gauss, mean: 10.0, std_deviation: 1.0}
```
Every error names file:line:col and what was expected (``diagnosis.yaml_source``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from yaml.nodes import Node

from detection.filters import DEVIATIONS, TYPES as FILTER_TYPES, FilterSpec
from detection.observation import is_observation_name
from detection.observer_set import ObserverSet
from detection.observers import KINDS, Observer, State
from detection.observers.activated import GRAPH_CHANNEL
from detection.observers.resource import RESOURCE_CHANNEL
from detection.state_tests import NOMINAL, OPTIONAL, NominalTest, QuantityTest, StudentT
from diagnosis.yaml_source import YamlSource

TOP_KEYS = ("main_loop_rate", "start_up_time", "setup")
GROUP = {"activated": "nodes", "resource": "nodes", "movement": "correlations"}  # others: topics
COMMON = ("literal", "start_up_time")
ENTRY_KEYS = {
    "activated": ("name", *COMMON),
    "resource": ("name", "process", "filter", "states", *COMMON),
    "timeout": ("name", "msg_type", "timeout", *COMMON),
    "hz": ("name", "msg_type", "filter", "states", *COMMON),
    "timestamp": ("name", "msg_type", "filter", "states", *COMMON),
    "timing": ("name_a", "name_b", "msg_type_a", "msg_type_b", "filter", "states", *COMMON),
    "score": ("name", "msg_type", "field", "filter", "states", *COMMON),
    "movement": ("source_a", "source_b", "differentiate", "filter", "states", *COMMON),
}
SOURCE_KEYS = ("topic", "field", "msg_type")
#: The largest count a configuration may give (a filter's window, a state's number): a million samples is
#: minutes of a 1 kHz topic, far beyond any observer's need, and far below what a deque can hold.
MAX_COUNT = 1_000_000
FILTER_KEYS = ("type", "window_size", "decay_rate", "k_size", "deviation_type")
STATE_KEYS = ("state", "number", "healthy")


@dataclass
class ObserverConfig:
    """A loaded configuration: the observers, and what a tap must provide for them."""
    path: str
    observers: list[Observer]
    rate_hz: float = 10.0
    topics: dict[str, str | None] = field(default_factory=dict)     # topic -> message type (None: discover)
    decoded: set[str] = field(default_factory=set)                  # topics whose fields are read
    stamped: set[str] = field(default_factory=set)                  # topics whose header stamp is read
    nodes: list[str] = field(default_factory=list)                  # activated: nodes watched in the graph
    processes: dict[str, str] = field(default_factory=dict)         # resource: node -> process pattern

    def build(self) -> ObserverSet:
        return ObserverSet(self.observers, self.rate_hz)


def load_observers(path: str | Path, text: str | None = None) -> ObserverConfig:
    """Read an observer configuration; raises ``SourceError`` (file:line:col) on bad input."""
    return _Loader(YamlSource(path, text)).load()


def atom_of(name: str) -> str:
    """``/robot1/scan`` -> ``robot1_scan``: a topic or node name as the argument of an observation."""
    return name.strip("/").replace("/", "_")


class _Loader:
    def __init__(self, source: YamlSource) -> None:
        self.s = source
        self.names: dict[str, Node] = {}

    # -- scalars ------------------------------------------------------------------------------------
    def number(self, node: Node, what: str, positive: bool = False) -> float:
        text = self.s.scalar(node, what)
        try:
            x = float(text)
        except ValueError:
            self.s.error(node, f"{what} must be a number, not {text!r}")
        if not math.isfinite(x) or positive and x <= 0:
            self.s.error(node, f"{what} must be a {'positive ' if positive else ''}finite number, not {text!r}")
        return x

    def integer(self, node: Node, what: str, minimum: int, maximum: int = MAX_COUNT) -> int:
        text = self.s.scalar(node, what)
        try:
            n = int(text)
        except ValueError:
            self.s.error(node, f"{what} must be a whole number, not {text!r}")
        if n < minimum:
            self.s.error(node, f"{what} must be at least {minimum}, not {n}")
        if n > maximum:  # a window of 10**400 samples raised OverflowError in the filter (issue 22's fuzzing)
            self.s.error(node, f"{what} must be at most {maximum}, not {text[:20]}{'...' if len(text) > 20 else ''}")
        return n

    def boolean(self, node: Node, what: str) -> bool:
        text = self.s.scalar(node, what).lower()
        if text not in ("true", "false"):
            self.s.error(node, f"{what} must be true or false, not {text!r}")
        return text == "true"

    def topic(self, node: Node, what: str) -> str:
        name = self.s.scalar(node, what)
        if not name.startswith("/") and not name.startswith("@"):
            name = "/" + name
        return name

    # -- structure ----------------------------------------------------------------------------------
    def load(self) -> ObserverConfig:
        s = self.s
        top = s.mapping(s.root, "an observer configuration")
        s.check_keys(top, TOP_KEYS, "an observer configuration")
        if "setup" not in top:
            s.error(s.root, "an observer configuration has a 'setup' list of observers")
        config = ObserverConfig(s.path, [])
        if "main_loop_rate" in top:
            config.rate_hz = self.number(top["main_loop_rate"][1], "main_loop_rate", positive=True)
        start_up = self.number(top["start_up_time"][1], "start_up_time") if "start_up_time" in top else 1.0
        for item in s.sequence(top["setup"][1], "setup"):
            self.observer(item, config, start_up)
        if not config.observers:
            s.error(top["setup"][1], "setup lists no observer")
        return config

    def observer(self, node: Node, config: ObserverConfig, start_up: float) -> None:
        s = self.s
        entries = s.mapping(node, "an observer")
        if "type" not in entries:
            s.error(node, f"an observer needs a 'type', one of: {', '.join(KINDS)}")
        kind = s.scalar(entries["type"][1], "type")
        if kind not in KINDS:
            s.error(entries["type"][1], f"unknown observer type {kind!r}; expected one of: {', '.join(KINDS)}")
        group = GROUP.get(kind, "topics")
        s.check_keys(entries, ("type", group, "start_up_time"), f"a {kind} observer")
        if group not in entries:
            s.error(node, f"a {kind} observer lists its {group}")
        if "start_up_time" in entries:
            start_up = self.number(entries["start_up_time"][1], "start_up_time")
        for item in s.sequence(entries[group][1], group):
            config.observers.append(self.entry(kind, item, config, start_up))

    def entry(self, kind: str, node: Node, config: ObserverConfig, start_up: float) -> Observer:
        s = self.s
        e = s.mapping(node, f"a {kind} entry")
        s.check_keys(e, ENTRY_KEYS[kind], f"a {kind} entry")
        required = {"timing": ("name_a", "name_b"), "movement": ("source_a", "source_b")}.get(kind, ("name",))
        for key in required + (("states",) if "states" in ENTRY_KEYS[kind] else ()):
            if key not in e:
                s.error(node, f"a {kind} entry needs '{key}'")
        if "start_up_time" in e:
            start_up = self.number(e["start_up_time"][1], "start_up_time")
        spec = self.filter(e["filter"][1]) if "filter" in e else FilterSpec()
        cls = KINDS[kind]
        kw: dict = {"filter_spec": spec, "start_up_time": start_up}
        if kind == "activated":
            name = self.s.scalar(e["name"][1], "name")
            channels, args = (GRAPH_CHANNEL,), [atom_of(name)]
            kw["node"] = name if name.startswith("/") else "/" + name
            config.nodes.append(kw["node"])
        elif kind == "resource":
            name = self.s.scalar(e["name"][1], "name")
            channels, args = (RESOURCE_CHANNEL + atom_of(name),), [atom_of(name)]
            kw["process"] = s.scalar(e["process"][1], "process") if "process" in e else atom_of(name)
            config.processes[atom_of(name)] = kw["process"]
        elif kind == "timing":
            a, b = self.topic(e["name_a"][1], "name_a"), self.topic(e["name_b"][1], "name_b")
            if a == b:
                s.error(e["name_b"][1], "timing needs two different topics")
            self.add_topic(config, a, e.get("msg_type_a"))
            self.add_topic(config, b, e.get("msg_type_b"))
            channels, args = (a, b), [atom_of(a), atom_of(b)]
        elif kind == "movement":
            (a, pa), (b, pb) = self.source(e["source_a"][1], config), self.source(e["source_b"][1], config)
            if (a, pa) == (b, pb):
                s.error(e["source_b"][1], "movement compares two different sources")
            channels, args = (a, b), [atom_of(a), atom_of(b)]
            kw["paths"] = (pa, pb)
            if "differentiate" in e:
                kw["differentiate"] = self.boolean(e["differentiate"][1], "differentiate")
        else:
            t = self.topic(e["name"][1], "name")
            self.add_topic(config, t, e.get("msg_type"))
            channels, args = (t,), [atom_of(t)]
            if kind == "timeout":
                kw["timeout"] = self.number(e["timeout"][1], "timeout", positive=True) if "timeout" in e else 1.0
            elif kind == "score":
                kw["field_path"] = self.path(e["field"][1]) if "field" in e else ("data",)
                config.decoded.add(t)
            elif kind == "timestamp":
                config.stamped.add(t)
        name = self.literal(kind, args, e, node)
        if "states" in e:
            kw["states"] = self.states(e["states"][1], cls.quantities, kind)
        return cls(name=name, channels=channels, **kw)

    def add_topic(self, config: ObserverConfig, topic: str, type_entry: tuple | None) -> None:
        msg_type = self.s.scalar(type_entry[1], "msg_type") if type_entry else None
        if msg_type is not None and msg_type.count("/") not in (1, 2):
            self.s.error(type_entry[1], f"msg_type is a ROS 2 type such as std_msgs/msg/Float64, not {msg_type!r}")
        known = config.topics.get(topic)
        if known and msg_type and known != msg_type:
            self.s.error(type_entry[1], f"topic {topic} was given type {known} elsewhere")
        config.topics[topic] = msg_type or known

    def source(self, node: Node, config: ObserverConfig) -> tuple[str, tuple[str, ...]]:
        e = self.s.mapping(node, "a movement source")
        self.s.check_keys(e, SOURCE_KEYS, "a movement source")
        for key in ("topic", "field"):
            if key not in e:
                self.s.error(node, f"a movement source needs '{key}' (e.g. topic: /imu, field: angular_velocity.z)")
        topic = self.topic(e["topic"][1], "topic")
        self.add_topic(config, topic, e.get("msg_type"))
        config.decoded.add(topic)
        return topic, self.path(e["field"][1])

    def path(self, node: Node) -> tuple[str, ...]:
        text = self.s.scalar(node, "field")
        parts = tuple(text.split("."))
        if not all(p.isidentifier() for p in parts):
            self.s.error(node, f"field is a dotted path such as twist.twist.angular.z, not {text!r}")
        return parts

    def literal(self, kind: str, args: list[str], e: dict, node: Node) -> str:
        if "literal" in e:
            lit_node = e["literal"][1]
            name = "".join(self.s.scalar(lit_node, "literal").split())
            expected = len(args)
            if not is_observation_name(name) or not name.startswith(kind + "(") or name.count(",") != expected - 1:
                self.s.error(lit_node, f"literal must be {kind}(...) with {expected} atom argument(s), e.g. "
                                       f"{kind}({', '.join(a.lower() or 'x' for a in args)})")
        else:
            lit_node = node
            name = f"{kind}({','.join(args)})"
            if not is_observation_name(name):
                self.s.error(node, f"{name} is not an observation literal (arguments are atoms: lowercase first, "
                                   f"letters, digits, _); give one with 'literal:'")
        if name in self.names:
            self.s.error(lit_node, f"observation {name} is emitted twice (also at line "
                                   f"{self.names[name].start_mark.line + 1})")
        self.names[name] = node
        return name

    def filter(self, node: Node) -> FilterSpec:
        s = self.s
        e = s.mapping(node, "a filter")
        s.check_keys(e, FILTER_KEYS, "a filter")
        kind = s.scalar(e["type"][1], "filter type") if "type" in e else "nofilter"
        if kind not in FILTER_TYPES:
            s.error(e["type"][1], f"unknown filter type {kind!r}; expected one of: {', '.join(FILTER_TYPES)}")
        window = self.integer(e["window_size"][1], "window_size", 1) if "window_size" in e else None
        if window is None and kind in ("median", "k_trimmed_mean"):
            s.error(node, f"a {kind} filter needs a window_size")
        kw: dict = {"type": kind, "window_size": window}
        if "decay_rate" in e:
            kw["decay_rate"] = self.number(e["decay_rate"][1], "decay_rate", positive=True)
            if kw["decay_rate"] > 1:
                s.error(e["decay_rate"][1], "decay_rate is between 0 and 1")
        if "k_size" in e:
            kw["k_size"] = self.integer(e["k_size"][1], "k_size", 0)
            if window is not None and 2 * kw["k_size"] >= window:
                s.error(e["k_size"][1], f"k_size {kw['k_size']} trims the whole window of {window}")
        if "deviation_type" in e:
            kw["deviation_type"] = s.scalar(e["deviation_type"][1], "deviation_type")
            if kw["deviation_type"] not in DEVIATIONS:
                s.error(e["deviation_type"][1], f"deviation_type is one of: {', '.join(DEVIATIONS)}")
        return FilterSpec(**kw)

    def states(self, node: Node, quantities: tuple[str, ...], kind: str) -> tuple[State, ...]:
        s = self.s
        out = []
        for item in s.sequence(node, "states"):
            e = s.mapping(item, "a state")
            s.check_keys(e, STATE_KEYS + quantities, f"a {kind} state")
            if "state" not in e:
                s.error(item, "a state needs a name ('state: nominal')")
            tests = tuple((q, self.test(e[q][1], q)) for q in quantities if q in e)
            if not tests:
                s.error(item, f"a {kind} state tests at least one of: {', '.join(quantities)}")
            out.append(State(s.scalar(e["state"][1], "state"), tests,
                             self.integer(e["number"][1], "number", 0) if "number" in e else None,
                             self.boolean(e["healthy"][1], "healthy") if "healthy" in e else True))
        if not out:
            s.error(node, "states lists at least one state")
        return tuple(out)

    def test(self, node: Node, quantity: str) -> QuantityTest:
        s = self.s
        e = s.mapping(node, f"the test of {quantity}")
        all_types = (*NOMINAL, "nominal_value", "student_t")
        if "type" not in e:
            s.error(node, f"the test of {quantity} needs a 'type', one of: {', '.join(all_types)}")
        kind = s.scalar(e["type"][1], "type")
        if kind == "student_t":
            s.check_keys(e, ("type", "true_mean", "significance_level", "std_deviation"), "a student_t test")
            for key in ("true_mean", "significance_level"):
                if key not in e:
                    s.error(node, f"a student_t test needs '{key}'")
            level = self.number(e["significance_level"][1], "significance_level", positive=True)
            if level >= 1:
                s.error(e["significance_level"][1], "significance_level is between 0 and 1, e.g. 0.05")
            sd = self.number(e["std_deviation"][1], "std_deviation", positive=True) if "std_deviation" in e else None
            return QuantityTest(student_t=StudentT(self.number(e["true_mean"][1], "true_mean"), level, sd))
        if kind == "nominal_value":
            s.check_keys(e, ("type", "value", "deviation"), "a nominal_value test")
            value = self.nominal(e["value"][1]) if "value" in e else None
            devs = tuple(self.nominal(d) for d in s.sequence(e["deviation"][1], "deviation")) if "deviation" in e else ()
            if value is None and not devs:
                s.error(node, "a nominal_value test has a 'value' test, a 'deviation' list, or both")
            return QuantityTest(value=value, deviation=devs)
        if kind not in NOMINAL:
            s.error(e["type"][1], f"unknown test type {kind!r}; expected one of: {', '.join(all_types)}")
        return QuantityTest(value=self.nominal(node))

    def nominal(self, node: Node) -> NominalTest:
        s = self.s
        e = s.mapping(node, "a nominal test")
        kind = s.scalar(e["type"][1], "type") if "type" in e else None
        if kind not in NOMINAL:
            s.error(e["type"][1] if "type" in e else node, f"a nominal test's type is one of: {', '.join(NOMINAL)}")
        params = NOMINAL[kind]
        s.check_keys(e, ("type", *params, *OPTIONAL.get(kind, ())), f"a {kind} test")
        values = []
        for p in params + OPTIONAL.get(kind, ()):
            if p not in e:
                if p in params:
                    s.error(node, f"a {kind} test needs {', '.join(params)}")
                continue
            values.append((p, self.number(e[p][1], p, positive=p in ("std_deviation", "n_sigma"))))
        d = dict(values)
        if "lower_bound" in d and d["lower_bound"] > d["upper_bound"]:
            s.error(e["upper_bound"][1], "upper_bound is below lower_bound")
        return NominalTest(kind, tuple(values))
