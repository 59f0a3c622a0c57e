"""The general system description: components, observations and formulas, in YAML.

```yaml
system: turtlebot_hardware          # name
components: [left_motor, right_motor]
observations: [commanded_forward, moved]   # what can be observed (true/false)
variables: [left_turns]             # internal propositions (optional)
behaviour:                          # healthy behaviour and fault modes, one formula per entry
  - "!AB(left_motor) & commanded_forward -> left_turns"
  - "AB(left_motor) -> !left_turns"          # a fault mode (strong fault model)
assumptions:                        # formulas that always hold and name no component (optional)
  - "moved -> left_turns | right_turns"
```
Every ``AB(c)`` must name a declared component and every other atom a declared observation or variable,
so a typo is an error (file:line:column) rather than a silently free proposition.
"""
from __future__ import annotations

from yaml.nodes import Node

from diagnosis.builder import ModelBuilder
from diagnosis.formula import Ab, FormulaSyntaxError, literals, parse_formula
from diagnosis.model import SystemModel
from diagnosis.yaml_source import YamlSource

SYSTEM_KEYS = ("system", "components", "observations", "variables", "behaviour", "behavior", "assumptions")


def load_system(source: YamlSource) -> SystemModel:
    top = source.mapping(source.root, "a system description")
    source.check_keys(top, SYSTEM_KEYS, "a system description")
    name = source.scalar(top["system"][1], "system")
    builder = ModelBuilder(name, source.path, "system")

    declared: dict[str, str] = {}  # name -> what it is, to reject one name declared twice
    for section, kind in (("components", "component"), ("observations", "observation"), ("variables", "variable")):
        if section not in top:
            if section == "components":
                source.error(top["system"][0], "a system description needs a 'components' list")
            continue
        for item, node in source.names(top[section][1], section):
            if item in declared:
                source.error(node, f"{item!r} is already declared as {declared[item]}")
            declared[item] = kind
            if kind == "component":
                builder.add_component(item)
            elif kind == "observation":
                builder.add_observable(item)
            else:
                builder.atom(item)

    for section in ("behaviour", "behavior", "assumptions"):
        if section in top:
            for node in source.sequence(top[section][1], section):
                _add_formula(source, builder, node, declared, allow_ab=section != "assumptions")
    return builder.build()


def _add_formula(source: YamlSource, builder: ModelBuilder, node: Node, declared: dict[str, str],
                 allow_ab: bool) -> None:
    text = source.scalar(node, "a formula")
    try:
        formula = parse_formula(text)
    except FormulaSyntaxError as exc:
        source.error(node, f"bad formula: {exc}", exc.column)
    for lit in literals(formula):
        if isinstance(lit, Ab):
            if declared.get(lit.component) != "component":
                source.error(node, f"AB({lit.component}): unknown component {lit.component!r}"
                                   f" (declared: {', '.join(builder.components)})")
            if not allow_ab:
                source.error(node, "assumptions name no component; put formulas with AB(...) under 'behaviour'")
        elif declared.get(lit.name) not in ("observation", "variable"):
            what = f" (it is a {declared[lit.name]}: write AB({lit.name}))" if lit.name in declared else \
                " (declare it under 'observations' or 'variables')"
            source.error(node, f"unknown proposition {lit.name!r}{what}")
    builder.add_formula(formula)
