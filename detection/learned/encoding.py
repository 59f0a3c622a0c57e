"""Every message as a vector of numbers, found generically, never written per message type.

ROS 2: the message class's ``rosidl`` introspection (``SLOT_TYPES``) is walked once per type: numbers
and booleans are taken as they are, strings and sequences by their length, small fixed arrays (≤ 9,
e.g. a quaternion) element by element; larger fixed arrays (covariances) and ``builtin_interfaces/Time``
are left out (a fixed length says nothing, an absolute time only says *when*). Zenoh: the decoded JSON
envelope, flattened the same way (numbers, lengths of strings and lists, nested objects by path).
Every vector starts with the message's size in bytes.
"""
from __future__ import annotations

import importlib
import json
from typing import Any, Callable, Sequence

import numpy as np

SIZE_COLUMN = "size"
SMALL_ARRAY = 9
SKIPPED_TYPES = {("builtin_interfaces", "msg", "Time")}


class EncodingError(ValueError):
    """A message that cannot be encoded (not the channel's type, not JSON)."""


def _message_class(namespaced: Any) -> type:
    module = importlib.import_module(".".join(namespaced.namespaces))
    return getattr(module, namespaced.name)


def _getter(path: tuple[str, ...]) -> Callable[[Any], Any]:
    def get(msg: Any) -> Any:
        for name in path:
            msg = getattr(msg, name)
        return msg
    return get


def _walk(cls: type, prefix: tuple[str, ...], out: list[tuple[str, Callable[[Any], float]]]) -> None:
    from rosidl_parser import definition as idl

    for name, slot in zip(cls.get_fields_and_field_types(), cls.SLOT_TYPES):
        path = (*prefix, name)
        label = ".".join(path)
        get = _getter(path)
        if isinstance(slot, idl.NamespacedType):
            if (*slot.namespaces, slot.name) not in SKIPPED_TYPES:
                _walk(_message_class(slot), path, out)
        elif isinstance(slot, idl.BasicType):
            if slot.typename in ("char", "octet"):
                out.append((label, lambda m, g=get: float(ord(v) if isinstance(v := g(m), (str, bytes)) else v)))
            else:
                out.append((label, lambda m, g=get: float(g(m))))
        elif isinstance(slot, idl.AbstractGenericString) or isinstance(slot, idl.AbstractSequence):
            out.append((f"{label}#len", lambda m, g=get: float(len(g(m)))))
        elif isinstance(slot, idl.Array):
            if isinstance(slot.value_type, idl.BasicType) and slot.size <= SMALL_ARRAY:
                for i in range(slot.size):
                    out.append((f"{label}[{i}]", lambda m, g=get, i=i: float(g(m)[i])))


class RosEncoder:
    """The numbers of one ROS 2 message type; built once per type from its introspection."""

    def __init__(self, msg_class: type) -> None:
        fields: list[tuple[str, Callable[[Any], float]]] = []
        _walk(msg_class, (), fields)
        self.msg_class = msg_class
        self.columns: list[str] = [SIZE_COLUMN] + [name for name, _ in fields]
        self._getters = [get for _, get in fields]

    @classmethod
    def for_type(cls, type_name: str) -> "RosEncoder":
        """``'nav_msgs/msg/Odometry'`` (as the ROS graph names it) → its encoder."""
        package, _, name = type_name.replace("/msg/", "/").rpartition("/")
        try:
            return cls(getattr(importlib.import_module(f"{package}.msg"), name))
        except (ImportError, AttributeError):
            raise EncodingError(f"unknown ROS 2 message type {type_name!r}") from None

    def encode(self, msg: Any, size: int) -> np.ndarray:
        """The vector of a deserialised ``msg`` that had ``size`` bytes on the wire."""
        return np.fromiter((size, *(get(msg) for get in self._getters)), dtype=np.float64,
                           count=len(self.columns))

    def encode_raw(self, data: bytes) -> np.ndarray:
        """The vector of a serialised (CDR) message."""
        from rclpy.serialization import deserialize_message
        return self.encode(deserialize_message(data, self.msg_class), len(data))


def flatten_json(value: Any, prefix: str = "") -> dict[str, float]:
    """Numbers by path; strings and lists by their length; objects recursively."""
    out: dict[str, float] = {}
    if isinstance(value, dict):
        for key, item in value.items():
            out.update(flatten_json(item, f"{prefix}.{key}" if prefix else str(key)))
    elif isinstance(value, bool):
        out[prefix] = float(value)
    elif isinstance(value, (int, float)):
        out[prefix] = float(value)
    elif isinstance(value, (str, list)):
        out[f"{prefix}#len"] = float(len(value))
    return out


def decode_json_lines(payload: bytes) -> list[tuple[int, Any]]:
    """The JSON values of a payload with their sizes in bytes: one per line (a batch of envelopes is
    JSON Lines; a single message is one line). Raises ``EncodingError`` when a line is not JSON."""
    return [(len(line), _load(line)) for line in payload.splitlines() if line.strip()]


def vector_of(size: int, flat: dict[str, float], index: dict[str, int]) -> np.ndarray:
    """A flattened JSON value as the vector of the columns in ``index`` (column → position, ``size``
    at 0); paths not in ``index`` are left out, columns not in ``flat`` are 0."""
    vector = np.zeros(len(index))
    vector[0] = size
    for key, number in flat.items():
        i = index.get(key)
        if i is not None:
            vector[i] = number
    return vector


def json_columns(paths) -> list[str]:
    """The columns of a JSON channel from the flattened paths seen on it: the size first, then sorted."""
    return [SIZE_COLUMN] + sorted(set(paths) - {SIZE_COLUMN})


class JsonEncoder:
    """The numbers of a JSON message (the Zenoh envelope); columns fixed from sample messages."""

    def __init__(self, columns: Sequence[str]) -> None:
        self.columns = [SIZE_COLUMN] + [c for c in columns if c != SIZE_COLUMN]
        self._index = {c: i for i, c in enumerate(self.columns)}

    @classmethod
    def from_samples(cls, payloads: Sequence[bytes]) -> "JsonEncoder":
        seen: dict[str, None] = {}
        for payload in payloads:
            for _, value in decode_json_lines(payload):
                seen.update(dict.fromkeys(flatten_json(value)))
        return cls(json_columns(seen))

    def encode(self, payload: bytes) -> list[np.ndarray]:
        """One vector per envelope in ``payload`` (a batch has several); unknown paths are ignored."""
        return [vector_of(size, flatten_json(value), self._index) for size, value in decode_json_lines(payload)]


def _load(line: bytes) -> Any:
    try:
        return json.loads(line)
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise EncodingError(f"not a JSON envelope: {exc}") from None
