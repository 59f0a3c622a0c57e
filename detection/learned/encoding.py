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

from detection.taps.ros2_take import HEAD_BYTES     # a type that ``reads_heads`` is read from this many bytes

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
        self._cdr: CdrColumns | bool | None = None          # built on first use

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

    @property
    def cdr(self) -> "CdrColumns | bool":
        """The in-place reader of this type (False when its layout does not allow one)."""
        if self._cdr is None:
            self._cdr = CdrColumns.for_class(self.msg_class, self.columns[1:])
        return self._cdr

    @property
    def head_bytes(self) -> int | None:
        """How many first bytes of a message suffice for its vector (``HEAD_BYTES``: every column
        comes before the message's bulk, as an image's header and sizes before its pixels), or None
        when the whole message is needed."""
        return HEAD_BYTES if self.cdr and self.cdr.reads_heads else None

    def encode_raw(self, data: bytes) -> np.ndarray:
        """The vector of a serialised (CDR) message: read in place (``CdrColumns``) when its layout
        allows, else deserialised by rclpy; the same numbers either way (tested). ``data`` may be the
        head of a longer message (``detection.taps.ros2_take.MessageHead``, its length in ``size``)."""
        if self.cdr:
            vector = self.cdr.read(data)
            if vector is not None:
                return vector
        if getattr(data, "size", len(data)) != len(data):
            raise EncodingError(f"the first {len(data)} of {data.size} bytes do not hold every number of a "
                                f"{self.msg_class.__name__} (its strings are longer than that)")
        from rclpy.serialization import deserialize_message
        return self.encode(deserialize_message(data, self.msg_class), len(data))


_CODES = {"boolean": "?", "octet": "B", "char": "B", "int8": "b", "uint8": "B", "int16": "h", "uint16": "H",
          "int32": "i", "uint32": "I", "int64": "q", "uint64": "Q", "float": "f", "double": "d"}


class _Unsupported(Exception):
    """A field type the in-place reader does not handle (wide strings, long double): rclpy decodes."""


def _plan(cls: type, prefix: tuple[str, ...], labels: list[str]) -> list[tuple]:
    """The CDR walk of ``cls`` as ``(kind, arg, column)`` steps; ``labels`` gets ``_walk``'s column
    names in the same order (columns are numbered by position in ``labels``)."""
    from rosidl_parser import definition as idl

    def element(slot) -> tuple:
        if isinstance(slot, idl.BasicType):
            if slot.typename not in _CODES:
                raise _Unsupported(slot.typename)
            return ("num", _CODES[slot.typename], None)
        if isinstance(slot, idl.AbstractString):
            return ("str", None, None)
        if isinstance(slot, idl.NamespacedType):
            return ("opaque", _plan(_message_class(slot), (), []), None)     # walked, no columns
        raise _Unsupported(type(slot).__name__)

    steps: list[tuple] = []
    for name, slot in zip(cls.get_fields_and_field_types(), cls.SLOT_TYPES):
        path = (*prefix, name)
        label = ".".join(path)
        if isinstance(slot, idl.NamespacedType):
            if (*slot.namespaces, slot.name) in SKIPPED_TYPES:
                steps.append(element(slot))
            else:
                steps.append(("struct", _plan(_message_class(slot), path, labels), None))
        elif isinstance(slot, idl.BasicType):
            kind, code, _ = element(slot)
            labels.append(label)
            steps.append((kind, code, len(labels) - 1))
        elif isinstance(slot, idl.AbstractString):
            labels.append(f"{label}#len")
            steps.append(("str", None, len(labels) - 1))
        elif isinstance(slot, idl.AbstractSequence):
            labels.append(f"{label}#len")
            steps.append(("seq", element(slot.value_type), len(labels) - 1))
        elif isinstance(slot, idl.Array):
            columns = None
            if isinstance(slot.value_type, idl.BasicType) and slot.size <= SMALL_ARRAY:
                columns = []
                for i in range(slot.size):
                    labels.append(f"{label}[{i}]")
                    columns.append(len(labels) - 1)
            steps.append(("arr", (element(slot.value_type), slot.size), columns))
        else:
            raise _Unsupported(type(slot).__name__)
    return steps


class CdrColumns:
    """An encoder's numbers read straight from the CDR bytes, without deserialising the message.

    Why: deserialising an Odometry with rclpy and walking its fields costs ~65 µs; reading the same
    numbers in place ~3 µs, which is what lets the learned detector watch a live team on a few % of
    a core. A message's layout (where each number is) depends only on the lengths of its strings and
    sequences; it is worked out once per message size by walking the type (classic little-endian CDR,
    as ROS 2 sends it: each primitive aligned to its size, at most 8, counted from after the 4-byte
    encapsulation header) and kept as one ``struct`` format. The next message of that size is read with
    it only if its length fields hold the same values (else, like a big-endian or non-ASCII message,
    ``read`` returns None and the caller deserialises).
    """

    MAX_LAYOUTS = 256           # distinct message sizes kept per type (JSON strings vary)

    def __init__(self, steps: list[tuple], width: int) -> None:
        self.steps, self.width = steps, width
        self._layouts: dict[int, tuple] = {}

    @classmethod
    def for_class(cls, msg_class: type, columns: list[str]) -> "CdrColumns | bool":
        """The reader for ``msg_class`` whose columns are ``columns`` (an encoder's, without ``size``);
        False when the type has a field it cannot read or its walk would not give those columns."""
        labels: list[str] = []
        try:
            steps = _plan(msg_class, (), labels)
        except (_Unsupported, ImportError, AttributeError):
            return False
        return cls(steps, len(columns) + 1) if labels == columns else False

    def read(self, data: bytes) -> np.ndarray | None:
        """The encoder's vector of ``data``, or None when this reader cannot vouch for it. ``data`` may
        be the head of a longer message (a ``MessageHead``, whose ``size`` is the message's length):
        the vector is the whole message's when every number lies in the head, else None."""
        size = getattr(data, "size", len(data))
        if len(data) < 4 or data[1] != 1:           # encapsulation: CDR little endian
            return None
        layout = self._layouts.get(size)
        if layout is not None and (len(data) < layout[6] or layout[1](values := layout[0](data)) != layout[2]):
            layout = None                           # same size, other string lengths: walk this one
        if layout is None:
            layout = self._layout(data, size)
            if layout is None:
                return None
            if len(self._layouts) >= self.MAX_LAYOUTS:
                self._layouts.clear()
            self._layouts[size] = layout
            values = layout[0](data)
        _, _, _, strings, pick, adjust, _ = layout
        for start, end in strings:
            if not data[start:end].isascii():       # a string's length in characters is not its bytes
                return None
        vector = np.array((size, *pick(values)), dtype=np.float64)
        vector -= adjust
        return vector

    @property
    def reads_heads(self) -> bool:
        """Whether every column comes before the type's bulk (the content of its sequences), so that a
        message's first bytes hold all its numbers: an image's header, sizes and pixel count come before
        its pixels; a ``CameraInfo``'s matrices after its distortion sequence (small anyway)."""
        def walk(steps, bulk: bool) -> tuple[bool, bool]:          # (a column after bulk, bulk seen)
            for kind, arg, column in steps:
                if kind == "struct":
                    late, bulk = walk(arg, bulk)
                    if late:
                        return True, bulk
                    continue
                if column is not None and bulk:
                    return True, bulk
                bulk = bulk or kind == "seq" or (kind == "opaque" and self._has_seq(arg))
            return False, bulk
        return not walk(self.steps, False)[0]

    @staticmethod
    def _has_seq(steps) -> bool:
        return any(kind == "seq" or (kind in ("struct", "opaque") and CdrColumns._has_seq(arg))
                   for kind, arg, _ in steps)

    def _layout(self, data: bytes, size: int) -> tuple | None:
        import struct

        fields: list[tuple[int, str, int | None, bool]] = []      # offset in data, code, column, is a length
        strings: list[tuple[int, int]] = []
        end = size - 4

        def length(pos: int, column: int | None) -> tuple[int, int]:
            pos += -pos % 4
            if pos + 4 > end or pos + 8 > len(data):            # past the message, or past a head of it
                raise IndexError
            fields.append((pos + 4, "I", column, True))
            return pos + 4, int.from_bytes(data[pos + 4:pos + 8], "little")

        def walk(steps, pos: int, keep: bool) -> int:
            for kind, arg, column in steps:
                column = column if keep else None
                if kind == "num":
                    size = struct.calcsize(arg)
                    pos += -pos % min(size, 8)
                    if column is not None:
                        fields.append((pos + 4, arg, column, False))
                    pos += size
                elif kind == "str":
                    pos, n = length(pos, column)
                    if column is not None and n:
                        strings.append((pos + 4, pos + 4 + n - 1))
                    pos += n
                elif kind == "struct":
                    pos = walk(arg, pos, keep)
                elif kind == "opaque":
                    pos = walk(arg, pos, False)
                elif kind == "seq":
                    pos, n = length(pos, column)
                    pos = skip(arg, n, pos)
                else:                                           # arr
                    item, count = arg
                    if column is not None:
                        size = struct.calcsize(item[1])
                        for c in column:
                            pos += -pos % min(size, 8)
                            fields.append((pos + 4, item[1], c, False))
                            pos += size
                    else:
                        pos = skip(item, count, pos)
                if pos > end:
                    raise IndexError
            return pos

        def skip(item: tuple, count: int, pos: int) -> int:
            if item[0] == "num":
                size = struct.calcsize(item[1])
                return pos + (-pos % min(size, 8)) + count * size if count else pos
            for _ in range(count):
                pos = walk([item], pos, False)
            return pos

        try:
            walk(self.steps, 0, True)
        except IndexError:
            return None
        fields.sort()
        fmt, at = "<", 0
        for offset, code, _, _ in fields:
            fmt += f"{offset - at}x{code}" if offset > at else code
            at = offset + struct.calcsize(code)
        need = max([at, *(stop for _, stop in strings)])
        if need > len(data):
            return None                                         # a number or string beyond the head
        unpack = struct.Struct(fmt).unpack_from
        length_at = [i for i, f in enumerate(fields) if f[3]]
        values = unpack(data)
        by_column = sorted((f[2], i) for i, f in enumerate(fields) if f[2] is not None)
        if [c for c, _ in by_column] != list(range(self.width - 1)):
            return None
        adjust = np.zeros(self.width)
        for column, i in by_column:
            if fields[i][3] and self._is_string(column):
                adjust[column + 1] = 1.0                        # CDR counts a string's NUL
        return (unpack, _getter_of(length_at), _getter_of(length_at)(values), tuple(strings),
                _getter_of([i for _, i in by_column]), adjust, need)

    def _is_string(self, column: int) -> bool:
        def find(steps) -> bool | None:
            for kind, arg, col in steps:
                if col == column:
                    return kind == "str"
                if kind == "struct":
                    found = find(arg)
                    if found is not None:
                        return found
            return None
        return bool(find(self.steps))


def _getter_of(indices: list[int]) -> Callable[[tuple], tuple]:
    """``values -> tuple(values[i] for i in indices)`` at C speed."""
    import operator
    if not indices:
        return lambda values: ()
    if len(indices) == 1:
        i = indices[0]
        return lambda values: (values[i],)
    return operator.itemgetter(*indices)


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
