"""jason_ros INI manifests: map an action or a perception to a plain ROS topic (or service).

Files written for jason_ros (``jason-lang/jason_ros``, ROS 1) load unchanged::

    [cmd_vel]                       ; action cmd_vel(LX, LY, LZ, AX, AY, AZ)
    method = topic
    name = /turtle1/cmd_vel
    msg_type = Twist
    dependencies = geometry_msgs.msg
    params_name = linear.x, linear.y, linear.z, angular.x, angular.y, angular.z
    params_type = float, float, float, float, float, float

    [DEFAULT]                       ; a perceptions manifest
    rate = 2
    [pose]
    name = /RosAria/pose
    msg_type = nav_msgs/Odometry
    args = pose.pose.position.x, pose.pose.position.y
    buf = update

``msg_type`` is ``pkg/Type`` or a bare type resolved in ``dependencies``; services use
``Type.Request`` (rospy's ``TypeRequest``). Parameter types are Python builtins (``float``, ``int``,
``bool``, ``str``), literal lists (``[float]``) or message arrays (``geometry_msgs/Point[](x,y)``).
Perception ``args`` are dotted fields, ``field[](a, b)`` for arrays. ``buf = add`` adds percepts,
anything else replaces the previous one. Parsing needs no ROS; only resolving the types does.
"""
from __future__ import annotations

import ast
import configparser
import importlib
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from agentspeak.errors import SourceError
from robot_bridge.protocol import Value

_ARRAY_TYPE = re.compile(r"^\s*([\w]+)/(\w+)\[\]\((.*)\)\s*$")
_ARRAY_ARG = re.compile(r"^\s*(\w+)\[\]\((.*)\)\s*$")
_SCALARS = {"float": float, "int": int, "str": str, "bool": None}


def _split(text: str) -> list[str]:
    """Split at commas outside parentheses and brackets."""
    parts, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(text[start:i].strip())
            start = i + 1
    tail = text[start:].strip()
    if tail or parts:
        parts.append(tail)
    return parts


@dataclass(frozen=True)
class Place:
    """Where a manifest entry was written, for error messages."""

    file: str
    text: str
    section: str

    def error(self, key: str | None, message: str) -> SourceError:
        lines = self.text.splitlines()
        line_no, source = None, None
        in_section = False
        for number, line in enumerate(lines, 1):
            stripped = line.strip()
            if stripped.startswith("["):
                in_section = stripped == f"[{self.section}]"
                if in_section and key is None:
                    line_no, source = number, line
                    break
                continue
            if in_section and key and re.match(rf"^\s*{re.escape(key)}\s*[=:]", line):
                line_no, source = number, line
                break
        where = f"[{self.section}]" + (f" {key}" if key else "")
        return SourceError(f"{where}: {message}", file=self.file, line=line_no,
                           column=1 if source is not None else None, source_line=source)


def _resolve_type(place: Place, msg_type: str, dependencies: str | None, service: bool) -> Any:
    """The message (or service) class a manifest entry names."""
    package, _, name = msg_type.strip().rpartition("/")
    module_name = f"{package}.{'srv' if service else 'msg'}" if package else (dependencies or "").strip()
    if not module_name:
        raise place.error("msg_type", f"{msg_type!r} names no package: write pkg/{msg_type} or set dependencies")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        key = "msg_type" if package else "dependencies"
        raise place.error(key, f"cannot import {module_name!r} ({exc})") from None
    try:
        return getattr(module, name)
    except AttributeError:
        raise place.error("msg_type", f"{module_name} has no type {name!r}") from None


def _set_field(obj: Any, dotted: str, value: Any) -> None:
    *path, last = dotted.strip().split(".")
    for attr in path:
        obj = getattr(obj, attr)
    setattr(obj, last, value)


def _get_field(obj: Any, dotted: str) -> Any:
    for attr in dotted.strip().split("."):
        obj = getattr(obj, attr)
    return obj


def _to_value(obj: Any) -> Value:
    """A message field as a protocol value: numbers and strings as they are, sequences as tuples."""
    if isinstance(obj, (bool, int, float, str)):
        return obj
    if hasattr(obj, "tolist"):
        obj = obj.tolist()
    if isinstance(obj, (list, tuple)):
        return tuple(_to_value(o) for o in obj)
    return str(obj)


@dataclass(frozen=True)
class ActionMapping:
    """One manifest action: its parameters set the named fields of a message sent to ``name``."""

    action: str
    method: str
    name: str
    msg_type: str
    dependencies: str | None
    params: tuple[tuple[str, str], ...]
    latch: bool
    place: Place = field(compare=False, repr=False)

    def message_class(self) -> Any:
        """The topic's message class, or the service class (``X``, with ``X.Request``)."""
        return _resolve_type(self.place, self.msg_type, self.dependencies, self.method == "service")

    def build(self, args: tuple[Value, ...]) -> Any:
        """The message (or service request) for ``args``; raises ``ValueError`` for bad arguments."""
        if len(args) != len(self.params):
            raise ValueError(f"{self.action} takes {len(self.params)} arguments "
                             f"({', '.join(n for n, _ in self.params)}), got {len(args)}")
        cls = self.message_class()
        msg = cls.Request() if self.method == "service" else cls()
        for (name, kind), value in zip(self.params, args):
            _set_field(msg, name, self._convert(name, kind, value))
        return msg

    def _convert(self, name: str, kind: str, value: Value) -> Any:
        array = _ARRAY_TYPE.match(kind)
        if array:
            element = _resolve_type(self.place, f"{array.group(1)}/{array.group(2)}", None, False)
            fields = _split(array.group(3))
            items = []
            for item in self._as_list(name, value):
                entry = element()
                for sub, sub_value in zip(fields, self._as_list(name, item)):
                    _set_field(entry, sub, sub_value)
                items.append(entry)
            return items
        if kind.startswith("["):
            return list(self._as_list(name, value))
        if kind == "bool":
            if isinstance(value, bool):
                return value
            return str(value).lower() in ("yes", "true", "t", "1")
        try:
            return _SCALARS[kind](value)          # type: ignore[misc]
        except (TypeError, ValueError):
            raise ValueError(f"{self.action}: {name} must be {kind}, got {value!r}") from None

    @staticmethod
    def _as_list(name: str, value: Value) -> tuple:
        if isinstance(value, str):
            try:
                value = ast.literal_eval(value)
            except (ValueError, SyntaxError):
                raise ValueError(f"{name} must be a list, got {value!r}") from None
        if not isinstance(value, (list, tuple)):
            raise ValueError(f"{name} must be a list, got {value!r}")
        return tuple(value)


@dataclass(frozen=True)
class PerceptionMapping:
    """One manifest perception: fields of every message on ``name`` become a percept's arguments."""

    perception: str
    name: str
    msg_type: str
    dependencies: str | None
    args: tuple[str, ...]
    update: bool
    rate: float
    place: Place = field(compare=False, repr=False)

    def message_class(self) -> Any:
        return _resolve_type(self.place, self.msg_type, self.dependencies, False)

    def values(self, msg: Any) -> tuple[Value, ...]:
        """The percept arguments read from ``msg``."""
        return tuple(self._read(msg, arg) for arg in self.args)

    def _read(self, msg: Any, arg: str) -> Value:
        array = _ARRAY_ARG.match(arg)
        if array:
            items = _get_field(msg, array.group(1))
            fields = _split(array.group(2))
            return tuple(tuple(self._read(item, f) for f in fields) for item in items)
        return _to_value(_get_field(msg, arg))


def _read_ini(path: str | Path) -> tuple[configparser.RawConfigParser, Place]:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise SourceError(f"cannot read manifest ({exc.strerror})", file=str(path)) from None
    reader = configparser.RawConfigParser()
    try:
        reader.read_string(text, source=str(path))
    except configparser.Error as exc:
        line = getattr(exc, "lineno", None)
        source = text.splitlines()[line - 1] if line and line <= len(text.splitlines()) else None
        raise SourceError(f"not an INI manifest: {exc.message.splitlines()[0]}", file=str(path),
                          line=line, column=1 if source else None, source_line=source) from None
    return reader, Place(str(path), text, "")


def _required(reader: configparser.RawConfigParser, place: Place, key: str) -> str:
    if not reader.has_option(place.section, key) or not reader.get(place.section, key).strip():
        raise place.error(None, f"missing '{key} = ...'")
    return reader.get(place.section, key).strip()


def load_actions(path: str | Path) -> dict[str, ActionMapping]:
    """Read a jason_ros actions manifest; raises ``SourceError`` naming file, line and problem."""
    reader, base = _read_ini(path)
    mappings = {}
    for section in reader.sections():
        place = Place(base.file, base.text, section)
        method = reader.get(section, "method", fallback="topic").strip()
        if method not in ("topic", "service"):
            raise place.error("method", f"method must be topic or service, got {method!r}")
        names = [n.strip() for n in _split(reader.get(section, "params_name", fallback=""))]
        kinds_text = reader.get(section, "params_type", fallback="")
        kinds = [k.strip() for k in _split(kinds_text)] if kinds_text.strip() else ["str"] * len(names)
        if len(kinds) != len(names):
            raise place.error("params_type", f"{len(names)} params_name but {len(kinds)} params_type")
        for kind in kinds:
            if kind not in _SCALARS and not kind.startswith("[") and not _ARRAY_TYPE.match(kind):
                raise place.error("params_type", f"unknown parameter type {kind!r}; expected float, "
                                  "int, bool, str, a [list] or pkg/Type[](fields)")
        mappings[section] = ActionMapping(
            section, method, _required(reader, place, "name"), _required(reader, place, "msg_type"),
            reader.get(section, "dependencies", fallback=None), tuple(zip(names, kinds)),
            reader.get(section, "latch", fallback="false").strip().lower() in ("yes", "true", "t", "1"),
            place)
    return mappings


def load_perceptions(path: str | Path) -> dict[str, PerceptionMapping]:
    """Read a jason_ros perceptions manifest; raises ``SourceError`` naming file, line and problem."""
    reader, base = _read_ini(path)
    try:
        rate = float(reader.defaults().get("rate", 30))
    except ValueError:
        raise Place(base.file, base.text, "DEFAULT").error("rate", "rate must be a number (Hz)") from None
    mappings = {}
    for section in reader.sections():
        place = Place(base.file, base.text, section)
        args = tuple(_split(reader.get(section, "args", fallback="")))
        mappings[section] = PerceptionMapping(
            section, _required(reader, place, "name"), _required(reader, place, "msg_type"),
            reader.get(section, "dependencies", fallback=None), args,
            reader.get(section, "buf", fallback="update").strip() != "add", rate, place)
    return mappings
