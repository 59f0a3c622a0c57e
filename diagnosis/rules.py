"""The fast rule engine of the paper's section V: rules react to observations and PosAb.

A rule ``(posObs, negObs, posPosAb, negPosAb, action)`` reacts to Obs, the set of observation literals
currently known (``hz(scan)`` when observed true, ``~hz(scan)`` when observed false), and PosAb, the
components possibly faulty. Two semantics:

* ``paper`` (default, the paper's section V): a rule fires unless its conditions are *contradicted*:
  no ``po`` in posObs has its complement in Obs (``~hz(scan)`` required, ``hz(scan)`` known), no
  literal of negObs is in Obs, and, once PosAb is known, no component of posPosAb is outside it and no
  component of negPosAb inside it. A missing observation blocks nothing; with no diagnosis yet
  (PosAb unknown, ``None``) the PosAb conditions block nothing either.
* ``strict`` (``semantics: strict`` in the file): the four set tests ``posObs ⊆ Obs``,
  ``negObs ∩ Obs = ∅``, ``posPosAb ⊆ PosAb``, ``negPosAb ∩ PosAb = ∅``.

Rules are evaluated only when Obs or PosAb change, and each rule fires at most once per change.

```yaml
semantics: paper                        # optional: paper (default) or strict
rules:                                  # next to the model: nav.yaml -> nav.rules.yaml
  - name: restart_laser
    posObs: [~hz(scan)]
    posPosAb: [laser_driver]
    negPosAb: [amcl]
    command: [ros2, lifecycle, set, /laser_driver, activate]   # or log / call / set_parameter / post
    timeout: 5
```
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping

import yaml
from yaml.nodes import Node

from diagnosis.actions import (Action, ActionEnvironment, ActionError, CallAction, CommandAction, LogAction,
                               PostAction, RuleContext, SetParameterAction)
from diagnosis.model import SystemModel
from diagnosis.service import observation_of
from diagnosis.yaml_source import YamlSource

log = logging.getLogger("faultmas.diagnosis.rules")
ACTION_KEYS = ("log", "call", "command", "set_parameter", "post")
SEMANTICS = ("paper", "strict")
RULE_KEYS = ("name", "posObs", "negObs", "posPosAb", "negPosAb", "timeout", *ACTION_KEYS)


@dataclass(frozen=True)
class Rule:
    name: str
    pos_obs: frozenset[str]
    neg_obs: frozenset[str]
    pos_posab: frozenset[str]
    neg_posab: frozenset[str]
    action: Action
    line: int | None = None
    strict: bool = False

    def applies(self, obs: frozenset[str], posab: frozenset[str] | None) -> bool:
        """Strict: the four set tests. Paper: no condition is contradicted by Obs or a known PosAb."""
        if self.strict:
            posab = posab or frozenset()
            return (self.pos_obs <= obs and not (self.neg_obs & obs)
                    and self.pos_posab <= posab and not (self.neg_posab & posab))
        if any(_complement(lit) in obs for lit in self.pos_obs) or self.neg_obs & obs:
            return False
        return posab is None or (self.pos_posab <= posab and not (self.neg_posab & posab))


def _complement(literal: str) -> str:
    return literal[1:] if literal.startswith("~") else f"~{literal}"


@dataclass(frozen=True)
class Firing:
    rule: Rule
    result: Any = None
    error: str | None = None


def known_literals(observations: Mapping[str, bool]) -> frozenset[str]:
    """Obs as a set of literal texts: ``name`` for true, ``~name`` for false."""
    return frozenset(name if value else f"~{name}" for name, value in observations.items())


class RuleEngine:
    """Holds the last Obs and PosAb; ``update`` runs the rules when either changed."""

    def __init__(self, rules: Iterable[Rule], environment: ActionEnvironment | None = None) -> None:
        self.rules = tuple(rules)
        self.environment = environment or ActionEnvironment()
        self._obs: frozenset[str] | None = None
        self._posab: frozenset[str] | None = None

    def update(self, observations: Mapping[str, bool], possibly_faulty: Iterable[str] | None) -> list[Firing]:
        """Run the rules if Obs or PosAb changed; ``possibly_faulty`` None: no diagnosis known yet."""
        obs = known_literals(observations)
        posab = None if possibly_faulty is None else frozenset(possibly_faulty)
        if obs == self._obs and posab == self._posab:
            return []
        self._obs, self._posab = obs, posab
        ctx_obs = dict(observations)
        fired = []
        for rule in self.rules:
            if rule.applies(obs, posab):
                ctx = RuleContext(rule.name, ctx_obs, posab or frozenset())
                try:
                    fired.append(Firing(rule, rule.action.run(ctx, self.environment)))
                except ActionError as exc:
                    log.error("%s", exc)
                    fired.append(Firing(rule, error=str(exc)))
        return fired


def rules_path_for(model_path: str | Path) -> Path:
    """Where a model's rules live: next to it, ``nav.yaml`` -> ``nav.rules.yaml``."""
    model_path = Path(model_path)
    return model_path.with_name(f"{model_path.stem}.rules.yaml")


def load_rules(path: str | Path, model: SystemModel | None = None, text: str | None = None) -> list[Rule]:
    """Rules from YAML; with a model, every observation and component they name must exist in it."""
    source = YamlSource(path, text)
    top = source.mapping(source.root, "a rules file")
    source.check_keys(top, ("semantics", "rules"), "a rules file")
    if "rules" not in top:
        source.error(source.root, "a rules file has a 'rules' list")
    strict = False
    if "semantics" in top:
        mode = source.scalar(top["semantics"][1], "semantics")
        if mode not in SEMANTICS:
            source.error(top["semantics"][1], f"semantics is {' or '.join(SEMANTICS)}, not {mode!r}")
        strict = mode == "strict"
    rules = []
    for i, node in enumerate(source.sequence(top["rules"][1], "rules")):
        rules.append(_rule(source, node, i, model, strict))
    return rules


def _rule(source: YamlSource, node: Node, index: int, model: SystemModel | None, strict: bool) -> Rule:
    entries = source.mapping(node, "a rule")
    source.check_keys(entries, RULE_KEYS, "a rule")
    name = source.scalar(entries["name"][1], "name") if "name" in entries else f"rule{index + 1}"
    sets = {}
    for key in ("posObs", "negObs", "posPosAb", "negPosAb"):
        items = source.names(entries[key][1], key) if key in entries else []
        for item, item_node in items:
            if model is None:
                continue
            if key.endswith("Obs"):
                obs_name, _ = observation_of(item)
                if obs_name not in model.observables:
                    source.error(item_node, f"rule {name}: {obs_name!r} is not an observation of model {model.name!r}")
            elif item not in model.ab_var:
                source.error(item_node, f"rule {name}: {item!r} is not a component of model {model.name!r}")
        if key.endswith("Obs"):
            sets[key] = frozenset(_literal(i) for i, _ in items)
        else:
            sets[key] = frozenset(i for i, _ in items)
    kinds = [k for k in ACTION_KEYS if k in entries]
    if len(kinds) != 1:
        source.error(node, f"rule {name}: give exactly one action among {', '.join(ACTION_KEYS)}")
    action = _action(source, kinds[0], entries[kinds[0]][1], entries, name)
    return Rule(name, sets["posObs"], sets["negObs"], sets["posPosAb"], sets["negPosAb"], action,
                node.start_mark.line + 1, strict)


def _literal(text: str) -> str:
    name, value = observation_of(text)
    return name if value else f"~{name}"


def _action(source: YamlSource, kind: str, value: Node, entries: dict, rule: str) -> Action:
    if kind == "log":
        return LogAction(source.scalar(value, "log"))
    if kind == "call":
        return CallAction(source.scalar(value, "call"))
    if kind == "command":
        argv = tuple(a for a, _ in source.names(value, "command")) if value.tag.endswith("seq") else None
        if not argv:
            source.error(value, f"rule {rule}: command is a non-empty argument list, e.g. [ros2, node, list]"
                                " (no shell)")
        timeout = 10.0
        if "timeout" in entries:
            t_node = entries["timeout"][1]
            try:
                timeout = float(source.scalar(t_node, "timeout"))
            except ValueError:
                source.error(t_node, f"rule {rule}: timeout is a number of seconds")
        return CommandAction(argv, timeout)
    fields = source.mapping(value, kind)
    if kind == "set_parameter":
        source.check_keys(fields, ("node", "name", "value"), "set_parameter")
        for k in ("node", "name", "value"):
            if k not in fields:
                source.error(value, f"rule {rule}: set_parameter needs node, name and value")
        return SetParameterAction(source.scalar(fields["node"][1], "node"), source.scalar(fields["name"][1], "name"),
                                  yaml.safe_load(yaml.serialize(fields["value"][1])))
    source.check_keys(fields, ("agent", "literal"), "post")
    for k in ("agent", "literal"):
        if k not in fields:
            source.error(value, f"rule {rule}: post needs agent and literal")
    return PostAction(source.scalar(fields["agent"][1], "agent"), source.scalar(fields["literal"][1], "literal"))
