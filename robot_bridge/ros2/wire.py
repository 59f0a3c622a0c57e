"""The JSON wire format on `jason/actions`, `jason/actions_status` and `jason/percepts`.

jason_ros's field names, carried as compact JSON in ``std_msgs/String`` (custom messages need a
rosidl build the wheels cannot do), plus the explicit ``id`` ROS 2 headers lack and rason's optional
failure ``reason``. Status is completion-based: sent when the motion has finished. Pure Python: no
rclpy here, so the format is testable and readable without ROS.

    {"agent_name":"faulty","action_name":"turn","parameters":["45"],"id":17}
    {"agent_name":"faulty","id":17,"result":false,"reason":"timeout"}
    {"agent_name":"","perception_name":"robot","parameters":["helper","-12","1.35","90"],"update":true}

A percept may also arrive as rason's whole literal: ``{"agent_name":"","literal":"robot(a,1,2,3)"}``,
or as a snapshot of everything one source perceives now, replacing that source's previous snapshot
(rason's ``perception`` message; percepts like ``moving``/``stopped`` exclude each other), valid for
``ttl`` seconds so that a silent sensor's percepts disappear:

    {"agent_name":"","source":"base","literals":["odom(0.5,0.0,0.0)","stopped"],"ttl":1.0}
"""
from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass

from robot_bridge.protocol import Percept, Value

__all__ = ["WireError", "ActionRequest", "ActionStatus", "Perception", "PerceptSnapshot", "decode_percepts", "format_value",
           "parse_value", "parse_literal", "format_literal"]


class WireError(ValueError):
    """A message on a jason/* topic that does not follow the wire format; quotes the message."""


def _load(text: str, required: dict[str, type | tuple[type, ...]]) -> dict:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise WireError(f"not JSON ({exc.msg} at column {exc.colno}): {text!r}") from None
    if not isinstance(data, dict):
        raise WireError(f"expected a JSON object, got {text!r}")
    for key, kind in required.items():
        if key not in data:
            raise WireError(f"missing field {key!r} in {text!r}")
        if not isinstance(data[key], kind) or (kind is int and isinstance(data[key], bool)):
            raise WireError(f"field {key!r} has the wrong type in {text!r}")
    return data


def _dump(data: dict) -> str:
    return json.dumps(data, separators=(",", ":"))


@dataclass(frozen=True)
class ActionRequest:
    """Agent → robot: perform ``action_name(parameters…)``; answer with the same ``id``."""

    agent_name: str
    action_name: str
    parameters: tuple[str, ...]
    id: int

    def to_json(self) -> str:
        return _dump({"agent_name": self.agent_name, "action_name": self.action_name,
                      "parameters": list(self.parameters), "id": self.id})

    @classmethod
    def from_json(cls, text: str) -> "ActionRequest":
        data = _load(text, {"action_name": str, "id": int})
        params = data.get("parameters", [])
        if not isinstance(params, list):
            raise WireError(f"field 'parameters' must be a list of strings in {text!r}")
        return cls(str(data.get("agent_name", "")), data["action_name"],
                   tuple(p if isinstance(p, str) else json.dumps(p) for p in params), data["id"])

    def values(self) -> tuple[Value, ...]:
        """The parameters as protocol values (numbers, atoms, tuples)."""
        return tuple(parse_value(p) for p in self.parameters)


@dataclass(frozen=True)
class ActionStatus:
    """Robot → agent: action ``id`` has finished (``result``) or failed (``reason``)."""

    agent_name: str
    id: int
    result: bool
    reason: str | None = None
    detail: str = ""

    def to_json(self) -> str:
        data: dict = {"agent_name": self.agent_name, "id": self.id, "result": self.result}
        if self.reason is not None:
            data["reason"] = self.reason
        if self.detail:
            data["detail"] = self.detail
        return _dump(data)

    @classmethod
    def from_json(cls, text: str) -> "ActionStatus":
        data = _load(text, {"id": int, "result": bool})
        reason = data.get("reason")
        return cls(str(data.get("agent_name", "")), data["id"], data["result"],
                   None if reason is None else str(reason), str(data.get("detail", "")))


@dataclass(frozen=True)
class Perception:
    """Robot → agent: a percept; ``update`` replaces percepts with the same name and arity."""

    agent_name: str
    perception_name: str
    parameters: tuple[str, ...]
    update: bool = True

    def to_json(self) -> str:
        return _dump({"agent_name": self.agent_name, "perception_name": self.perception_name,
                      "parameters": list(self.parameters), "update": self.update})

    @classmethod
    def from_percept(cls, percept: Percept, agent_name: str = "", update: bool = True) -> "Perception":
        return cls(agent_name, percept.name, tuple(format_value(a) for a in percept.args), update)

    @classmethod
    def from_json(cls, text: str) -> "Perception":
        data = _load(text, {})
        if "literal" in data:                       # rason: a whole literal string
            percept = parse_literal(str(data["literal"]))
            return cls(str(data.get("agent_name", "")), percept.name,
                       tuple(format_value(a) for a in percept.args), bool(data.get("update", True)))
        if not isinstance(data.get("perception_name"), str):
            raise WireError(f"missing field 'perception_name' (or 'literal') in {text!r}")
        params = data.get("parameters", [])
        if not isinstance(params, list):
            raise WireError(f"field 'parameters' must be a list of strings in {text!r}")
        return cls(str(data.get("agent_name", "")), data["perception_name"],
                   tuple(p if isinstance(p, str) else json.dumps(p) for p in params),
                   bool(data.get("update", True)))

    def percept(self) -> Percept:
        return Percept(self.perception_name, tuple(parse_value(p) for p in self.parameters))


@dataclass(frozen=True)
class PerceptSnapshot:
    """Robot → agent: all percepts of ``source`` now; replaces the previous snapshot of ``source``."""

    agent_name: str
    source: str
    percepts: tuple[Percept, ...]
    ttl: float | None = None

    def to_json(self) -> str:
        data: dict = {"agent_name": self.agent_name, "source": self.source,
                      "literals": [format_literal(p) for p in self.percepts]}
        if self.ttl is not None:
            data["ttl"] = self.ttl
        return _dump(data)

    @classmethod
    def from_json(cls, text: str) -> "PerceptSnapshot":
        data = _load(text, {"source": str, "literals": list})
        ttl = data.get("ttl")
        if ttl is not None and (isinstance(ttl, bool) or not isinstance(ttl, (int, float))):
            raise WireError(f"field 'ttl' must be a number of seconds in {text!r}")
        return cls(str(data.get("agent_name", "")), data["source"],
                   tuple(parse_literal(str(lit)) for lit in data["literals"]),
                   None if ttl is None else float(ttl))


def decode_percepts(text: str) -> "Perception | PerceptSnapshot":
    """Whatever arrived on ``jason/percepts``: a single perception or a source's snapshot."""
    data = _load(text, {})
    return PerceptSnapshot.from_json(text) if "literals" in data else Perception.from_json(text)


# --- term text <-> protocol values ------------------------------------------------------------

_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*([eE][+-]?\d+)?|\.\d+([eE][+-]?\d+)?)$")
_FUNCTOR = re.compile(r"^\s*([a-z][A-Za-z0-9_]*)\s*(\((.*)\))?\s*$", re.S)


def format_value(value: Value) -> str:
    """The term text of a value: ``0.5`` → ``"0.5"``, ``("a", 1)`` → ``"[a,1]"``, ``True`` → ``"true"``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value) or math.isinf(value):
            raise ValueError(f"{value!r} has no term text")
        return repr(value)
    if isinstance(value, (tuple, list)):
        return "[" + ",".join(format_value(v) for v in value) + "]"
    return str(value)


def _split_top(text: str) -> list[str]:
    """Split at commas that are outside brackets, parentheses and quotes."""
    parts, depth, quote, start = [], 0, "", 0
    for i, ch in enumerate(text):
        if quote:
            if ch == quote and text[i - 1] != "\\":
                quote = ""
        elif ch in "\"'":
            quote = ch
        elif ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
            if depth < 0:
                raise WireError(f"unbalanced brackets in {text!r}")
        elif ch == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    if depth or quote:
        raise WireError(f"unbalanced brackets or quotes in {text!r}")
    parts.append(text[start:])
    return parts


def parse_value(text: str) -> Value:
    """A term text as a value: numbers become ``int``/``float``, ``[a,b]`` a tuple, the rest a string.

    As in jason_ros, anything that is not a number or a list falls back to its (unquoted) text.
    """
    s = text.strip()
    if _NUMBER.match(s):
        return float(s) if any(c in s for c in ".eE") else int(s)
    if s.startswith("[") and s.endswith("]"):
        inner = s[1:-1].strip()
        return tuple(parse_value(p) for p in _split_top(inner)) if inner else ()
    if len(s) >= 2 and s[0] == s[-1] and s[0] in "\"'":
        return s[1:-1]
    return s


def parse_literal(text: str) -> Percept:
    """``"robot(helper,-12,1.35,90)"`` → ``Percept("robot", ("helper", -12, 1.35, 90))``."""
    match = _FUNCTOR.match(text)
    if not match:
        raise WireError(f"expected a literal like name(arg, ...), got {text!r}")
    body = match.group(3)
    if body is None:
        return Percept(match.group(1))
    args = tuple(parse_value(p) for p in _split_top(body)) if body.strip() else ()
    return Percept(match.group(1), args)


def format_literal(percept: Percept) -> str:
    """The inverse of :func:`parse_literal`."""
    if not percept.args:
        return percept.name
    return f"{percept.name}({','.join(format_value(a) for a in percept.args)})"
