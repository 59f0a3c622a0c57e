"""The paper's software-architecture models: nodes, topics, fault propagation and observation kinds.

```yaml
architecture: navigation
nodes:
  laser_driver: {pub: [scan]}
  amcl: {sub: [scan, odom], pub: [pose]}
assumptions:            # optional; each is AB(name), 'held' (never abnormal, default) or 'candidate'
  movement: held
observations:           # each observation is an atom; its name is its text without spaces
  - hz(scan)
  - timing(scan, pose)
  - movement(odom, imu)
```
Encoding, exactly the paper's formulas (n a node, m a topic):
fault propagation ``AB(m) -> OR over producers n of (AB(n) | OR AB(m_in) for m_in in sub(n))``;
``activated(n)``, ``resource(n)``: ``!obs -> AB(n)``; ``timeout(m)``, ``hz(m)``, ``timestamp(m)``,
``score(m)``: ``!obs -> AB(m)``; ``timing(m1,m2)``: ``!obs -> AB(m1) | AB(m2)``;
``movement(m1,m2)``: ``!obs -> AB(m1) | AB(m2) | AB(movement)``.
Only nodes (and assumptions marked ``candidate``) are diagnosis candidates; topic literals are internal.
A true observation constrains nothing (the formulas are one-directional, as in the paper).
Known limit: in a cycle of topics every AB(m) on the cycle can support the others, so a fault observed
only inside a feedback loop may be explained by no node at all.
"""
from __future__ import annotations

from diagnosis.builder import ModelBuilder
from diagnosis.formula import Ab, Atom, FormulaSyntaxError, atom_text, parse_formula
from diagnosis.model import SystemModel
from diagnosis.yaml_source import YamlSource

ARCHITECTURE_KEYS = ("architecture", "nodes", "assumptions", "observations")
NODE_KEYS = ("pub", "sub")
# kind -> what its arguments are
OBSERVATION_KINDS: dict[str, tuple[str, ...]] = {
    "activated": ("node",), "resource": ("node",),
    "timeout": ("topic",), "hz": ("topic",), "timestamp": ("topic",), "score": ("topic",),
    "timing": ("topic", "topic"), "movement": ("topic", "topic"),
}
MOVEMENT_ASSUMPTION = "movement"


def load_architecture(source: YamlSource) -> SystemModel:
    top = source.mapping(source.root, "an architecture model")
    source.check_keys(top, ARCHITECTURE_KEYS, "an architecture model")
    name = source.scalar(top["architecture"][1], "architecture")
    builder = ModelBuilder(name, source.path, "architecture")
    if "nodes" not in top:
        source.error(top["architecture"][0], "an architecture model needs 'nodes'")

    producers: dict[str, list[str]] = {}
    inputs: dict[str, list[str]] = {}
    subscriptions = []  # (node, topic, yaml node), checked once every publisher is known
    for node_name, (key, value) in source.mapping(top["nodes"][1], "nodes").items():
        entries = source.mapping(value, f"node {node_name!r}") if value.tag != "tag:yaml.org,2002:null" else {}
        source.check_keys(entries, NODE_KEYS, f"node {node_name!r}")
        builder.add_component(node_name)
        subs = source.names(entries["sub"][1], "sub") if "sub" in entries else []
        inputs[node_name] = [t for t, _ in subs]
        subscriptions.extend((node_name, t, item) for t, item in subs)
        for topic, _ in (source.names(entries["pub"][1], "pub") if "pub" in entries else []):
            producers.setdefault(topic, []).append(node_name)
    for node_name, topic, item in subscriptions:
        if topic not in producers:
            source.error(item, f"node {node_name!r} subscribes to topic {topic!r} but no node publishes it")

    def topic_ab(topic: str) -> int:
        return builder.variable(("ABtopic", topic))

    for topic, nodes in producers.items():  # AB(m) -> OR_n (AB(n) | OR AB(m_in))
        causes = []
        for n in nodes:
            causes.append(builder.ab(n))
            causes.extend(topic_ab(t) for t in inputs[n])
        builder.add_clause([-topic_ab(topic), *dict.fromkeys(causes)])

    assumptions: dict[str, int] = {}
    if "assumptions" in top:
        for a_name, (key, value) in source.mapping(top["assumptions"][1], "assumptions").items():
            mode = source.scalar(value, f"assumption {a_name!r}")
            if mode not in ("held", "candidate"):
                source.error(value, f"assumption {a_name!r} must be 'held' or 'candidate', not {mode!r}")
            if a_name in inputs:
                source.error(key, f"assumption {a_name!r} has the name of a node")
            assumptions[a_name] = builder.ab(a_name)
            if mode == "candidate":
                builder.components.append(a_name)
            else:
                builder.held.append(-assumptions[a_name])

    for item in (source.sequence(top["observations"][1], "observations") if "observations" in top else []):
        text = source.scalar(item, "an observation")
        try:
            atom = parse_formula(text)
        except FormulaSyntaxError as exc:
            source.error(item, f"bad observation: {exc}", exc.column)
        if not isinstance(atom, Atom) or "(" not in atom.name:
            source.error(item, f"an observation is kind(argument, ...), one of: {', '.join(OBSERVATION_KINDS)}")
        kind, args = atom.name[:-1].split("(", 1)
        arg_list = args.split(",")
        expected = OBSERVATION_KINDS.get(kind)
        if expected is None:
            source.error(item, f"unknown observation kind {kind!r}; expected one of: {', '.join(OBSERVATION_KINDS)}")
        if len(arg_list) != len(expected):
            source.error(item, f"{kind} takes {len(expected)} argument(s) ({', '.join(expected)}), got {len(arg_list)}")
        conclusion = []
        for arg, what in zip(arg_list, expected):
            if what == "node":
                if arg not in inputs:
                    source.error(item, f"{kind}({arg}): unknown node {arg!r}")
                conclusion.append(builder.ab(arg))
            else:
                if arg not in producers:
                    source.error(item, f"{kind}(...): topic {arg!r} is published by no node")
                conclusion.append(topic_ab(arg))
        if kind == "movement":
            if MOVEMENT_ASSUMPTION not in assumptions:
                assumptions[MOVEMENT_ASSUMPTION] = builder.ab(MOVEMENT_ASSUMPTION)
                builder.held.append(-assumptions[MOVEMENT_ASSUMPTION])
            conclusion.append(assumptions[MOVEMENT_ASSUMPTION])
        name = atom_text(kind, arg_list)
        if name in builder.observables:
            source.error(item, f"observation {name} is listed twice")
        obs = builder.add_observable(name, kind)
        builder.add_clause([obs, *conclusion])  # !obs -> conclusion
    return builder.build()


__all__ = ["load_architecture", "OBSERVATION_KINDS", "Ab"]
