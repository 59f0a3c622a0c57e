"""The one message envelope every faultmas agent speaks on the wire, and its strict decoder.

Encoding: compact JSON (no spaces, short keys). Why JSON and not msgpack: it is readable on the wire
(``z_sub`` or a packet capture shows the speech act as text), any language can speak it without a
schema, it adds no dependency, and the payload is dominated by the AgentSpeak content string, which
msgpack would not shrink. Measured in ``benchmarks/bench_zenoh.py``: encode+decode costs a few µs per
message, well under the network cost.

Wire form (version 1)::

    {"v":1,"id":"5f1c0a9e2b7d.12","mas":"rescue","from":"alice","to":["bob"],
     "perf":"tell","content":"position(3,4)","re":"8a0b11c2d3e4.7"}

``re`` (``in_reply_to``) is left out when the message answers nothing. ``content`` is AgentSpeak
text; parsing it is the agent layer's job (with the interpreter's own parser).

Batch form: several envelopes for one receiver in one network message, each encoded as above, one
per line (JSON Lines; an encoded envelope has no raw newline, JSON escapes it inside strings). A
receiver checks and delivers each line as if it had come alone, in order; the batch as a whole may
be up to ``BATCH_BYTES`` even where the per-message limit is lower. A sender batches only what its
agents send in a burst (``outbox.Outbox``), so a lone question is still one message.
"""
from __future__ import annotations

import itertools
import json
import re
import uuid
from dataclasses import dataclass, field
from typing import Any

from agentspeak.errors import FaultmasError

VERSION = 1

#: The speech-act performatives of Jason, the only ones accepted. Answers to ``askOne``/``askAll``/
#: ``askHow`` travel, as in Jason, as ``tell``/``tellHow`` messages whose ``in_reply_to`` names the
#: question, so no extra answer performative is needed.
PERFORMATIVES: frozenset[str] = frozenset({
    "tell", "untell", "achieve", "unachieve", "askOne", "askAll",
    "tellHow", "untellHow", "askHow", "signal",
})

#: Performatives whose sender waits for an answer.
QUESTIONS: frozenset[str] = frozenset({"askOne", "askAll", "askHow"})

#: Reasons a received message is dropped; the agent layer counts drops by these names.
DROP_REASONS: tuple[str, ...] = (
    "too_large", "not_json", "bad_version", "missing_field", "bad_field_type",
    "unknown_performative", "foreign_mas", "not_addressed", "duplicate_field",
)

#: Default limit on an encoded message, in bytes (configurable per transport).
DEFAULT_MAX_SIZE = 256 * 1024

#: Between the envelopes of a batch (see the module's docstring).
BATCH_SEPARATOR = b"\n"

#: A sender's batches are at most this many bytes (a bigger message goes alone).
BATCH_BYTES = 64 * 1024

# A name must be one Zenoh key-expression chunk: no '/', no wildcard or selector characters.
_NAME = re.compile(r"[^/*$?#\s]+")

_quote = json.encoder.encode_basestring  # a JSON string literal (C implementation), non-ASCII kept
_CONTROL_BYTES = bytes(range(32))


def _quote_content(text: str) -> str:
    """``_quote`` for the content, which may be KBs: an ASCII text without control characters needs
    only its quotes and backslashes escaped, done by ``str.replace`` (C, memchr speed); ``_quote``
    walks every character (~4 ns each, 17 µs for 4 KB) but wins below a few hundred."""
    if len(text) > 200 and text.isascii():
        raw = text.encode()
        if len(raw.translate(None, _CONTROL_BYTES)) == len(raw):
            return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return _quote(text)
_PROCESS_PREFIX = uuid.uuid4().hex[:12]
_COUNTER = itertools.count(1)


def new_message_id() -> str:
    """An id unique across processes: a random per-process prefix and a counter (cheap, sortable)."""
    return f"{_PROCESS_PREFIX}.{next(_COUNTER)}"


_KNOWN_NAMES: set[str] = set()  # names already checked (bounded: hostile input cannot grow it much)


def is_valid_name(name: object) -> bool:
    """True when ``name`` can be an agent or MAS name (one key-expression chunk)."""
    if type(name) is str and name in _KNOWN_NAMES:
        return True
    if not isinstance(name, str) or _NAME.fullmatch(name) is None:
        return False
    if len(_KNOWN_NAMES) < 10_000:
        _KNOWN_NAMES.add(name)
    return True


class BadMessage(FaultmasError, ValueError):
    """A received message that is dropped; ``reason`` is one of ``DROP_REASONS`` (or, in the secure profile,
    of ``identity.IDENTITY_DROP_REASONS``)."""

    def __init__(self, reason: str, detail: str = "", sender: str | None = None) -> None:
        self.reason = reason
        self.detail = detail
        self.sender = sender
        super().__init__(f"{reason}: {detail}" if detail else reason)


@dataclass(frozen=True, slots=True)
class Envelope:
    """One speech act from ``sender`` to every name in ``receivers`` within the MAS ``mas``."""

    mas: str
    sender: str
    receivers: tuple[str, ...]
    performative: str
    content: str
    in_reply_to: str | None = None
    message_id: str = field(default_factory=new_message_id)
    version: int = VERSION

    def __post_init__(self) -> None:
        if type(self.receivers) is not tuple:
            if isinstance(self.receivers, str):  # a single name is a common slip; accept it
                object.__setattr__(self, "receivers", (self.receivers,))
            elif isinstance(self.receivers, list):
                object.__setattr__(self, "receivers", tuple(self.receivers))
        self.validate()

    def validate(self) -> None:
        """Raise ``BadMessage`` if a field is wrong; used for local delivery and before encoding."""
        _check_fields(self.version, self.message_id, self.mas, self.sender, self.receivers,
                      self.performative, self.content, self.in_reply_to)

    def reply(self, performative: str, content: str, sender: str | None = None) -> "Envelope":
        """The answer to this message from ``sender`` (default: its first receiver), with ``in_reply_to`` set."""
        return Envelope(self.mas, sender or self.receivers[0], (self.sender,), performative, content,
                        in_reply_to=self.message_id)

    def encode(self) -> bytes:
        """Compact JSON bytes (UTF-8), written directly: 3x faster than building a dict for ``json``."""
        quote = _quote
        text = (f'{{"v":{self.version},"id":{quote(self.message_id)},"mas":{quote(self.mas)},'
                f'"from":{quote(self.sender)},"to":[{",".join(map(quote, self.receivers))}],'
                f'"perf":{quote(self.performative)},"content":{_quote_content(self.content)}')
        if self.in_reply_to is not None:
            text += f',"re":{quote(self.in_reply_to)}'
        return (text + "}").encode()


def split_batch(payload: bytes) -> list[bytes]:
    """The messages in one received payload: itself, or each line of a batch. A payload whose first
    line is not a whole JSON object is one message written over several lines (by hand, say)."""
    if BATCH_SEPARATOR not in payload:
        return [payload]
    lines = payload.split(BATCH_SEPARATOR)
    if not lines[0].rstrip().endswith(b"}"):
        return [payload]
    return [line for line in lines if line]


class _DuplicateField(ValueError):
    pass


def _unique_fields(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object whose keys are all different: with a key twice (``"from"``, say) json keeps the
    last, so a checker and a receiver could each read another value. Refused instead."""
    data = dict(pairs)
    if len(data) != len(pairs):
        seen: set[str] = set()
        twice = next(key for key, _ in pairs if key in seen or seen.add(key))
        raise _DuplicateField(twice)
    return data


_DECODER = json.JSONDecoder(object_pairs_hook=_unique_fields)
_scan = _DECODER.scan_once  # json.loads without its wrappers (~1.3 µs less per message)
_scan_string = json.decoder.scanstring  # one JSON string (C), with json's own rules

# The form ``Envelope.encode`` writes for one receiver, up to the content's opening quote. A JSON
# string without backslashes and control characters is its own value, so these groups are the
# values json would give; anything else (spaces, other key order, escapes) takes the general path.
_PLAIN = r'([^"\\\x00-\x1f]*)'
_OWN_FORM = re.compile(r'\{"v":1,"id":"%s","mas":"%s","from":"%s","to":\["%s"\],"perf":"%s","content":"'
                       % ((_PLAIN,) * 5))
_REPLY_END = re.compile(r',"re":"%s"\}\Z' % _PLAIN)


def _read_own_form(text: str) -> Envelope | None:
    """The envelope in ``text`` if it is in this encoder's own form with usual fields, else None:
    one pattern match and one C string scan instead of a JSON object and a dict (~2 µs less)."""
    head = _OWN_FORM.match(text)
    if head is None:
        return None
    try:
        content, end = _scan_string(text, head.end())
    except ValueError:
        return None
    if end == len(text) - 1 and text[end] == "}":
        in_reply_to = None
    else:
        tail = _REPLY_END.match(text, end)
        if tail is None:
            return None
        in_reply_to = tail.group(1)
    message_id, mas, sender, receiver, performative = head.groups()
    return _usual(mas, sender, (receiver,), performative, content, in_reply_to, message_id)


def decode(payload: bytes | bytearray | memoryview, max_size: int = DEFAULT_MAX_SIZE) -> Envelope:
    """Parse and check one received message; raise ``BadMessage`` naming why it is refused."""
    if len(payload) > max_size:
        raise BadMessage("too_large", f"{len(payload)} bytes > limit {max_size}")
    try:
        text = bytes(payload).decode()  # str: skips json's encoding detection
        envelope = _read_own_form(text)
        if envelope is not None:
            return envelope
        try:
            data, end = _scan(text, 0)
            if end != len(text):
                raise ValueError
        except _DuplicateField:
            raise
        except (StopIteration, ValueError):  # not a bare object: json decides, and says why
            data = _DECODER.decode(text)
    except _DuplicateField as twice:
        raise BadMessage("duplicate_field", f"{str(twice)[:40]!r} given twice") from None
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:  # RecursionError: nested too deep
        raise BadMessage("not_json", str(exc)[:80] or type(exc).__name__) from None
    envelope = _decode_well_formed(data)
    return envelope if envelope is not None else _refuse(data)


_new = object.__new__
_set = object.__setattr__


def _decode_well_formed(data: Any) -> Envelope | None:
    """The fast path for the usual message (names seen before): the same checks as ``Envelope``,
    inlined; ``None`` sends anything unusual to the slow path, which names the problem."""
    if type(data) is not dict:
        return None
    try:
        version, message_id, mas, sender, to, performative, content = (
            data["v"], data["id"], data["mas"], data["from"], data["to"], data["perf"], data["content"])
    except KeyError:
        return None
    if version != VERSION or type(version) is not int or type(to) is not list:
        return None
    return _usual(mas, sender, tuple(to), performative, content, data.get("re"), message_id)


def make_envelope(mas: str, sender: str, receivers: tuple[str, ...], performative: str, content: str,
                  in_reply_to: str | None, message_id: str) -> Envelope:
    """``Envelope(...)`` for the agent layer's own messages: the usual fields (names seen before, a
    known performative) pass in a few set lookups; anything else gets the full checks (``BadMessage``)."""
    envelope = _usual(mas, sender, receivers, performative, content, in_reply_to, message_id)
    if envelope is None:
        envelope = Envelope(mas, sender, receivers, performative, content, in_reply_to, message_id)
    return envelope


def _usual(mas: Any, sender: Any, receivers: tuple, performative: Any, content: Any, in_reply_to: Any,
           message_id: Any) -> Envelope | None:
    """An envelope of these fields if each is as usual (what ``_check_fields`` accepts), else None."""
    known = _KNOWN_NAMES
    try:
        if not (type(message_id) is str and message_id and mas in known and sender in known and receivers
                and known.issuperset(receivers) and performative in PERFORMATIVES and type(content) is str
                and (in_reply_to is None or (type(in_reply_to) is str and in_reply_to))):
            return None
    except TypeError:  # an unhashable "name" (a list, say): the slow path says what is wrong
        return None
    envelope = _new(Envelope)
    _set(envelope, "mas", mas)
    _set(envelope, "sender", sender)
    _set(envelope, "receivers", receivers)
    _set(envelope, "performative", performative)
    _set(envelope, "content", content)
    _set(envelope, "in_reply_to", in_reply_to)
    _set(envelope, "message_id", message_id)
    _set(envelope, "version", VERSION)
    return envelope


def _refuse(data: Any) -> Envelope:
    """The slow path: check field by field, raise ``BadMessage`` naming the first problem (or build
    the envelope if it is only unusual, e.g. new names)."""
    if not isinstance(data, dict):
        raise BadMessage("not_json", f"expected a JSON object, got {type(data).__name__}")
    sender = data.get("from")
    sender = sender if isinstance(sender, str) else None
    if "v" not in data:
        raise BadMessage("missing_field", "v", sender)
    if not _is_version(data["v"]):
        raise BadMessage("bad_version", f"version {data['v']!r}, this build speaks {VERSION}", sender)
    try:
        fields = (data["mas"], data["from"], data["to"], data["perf"], data["content"])
        message_id = data["id"]
    except KeyError as missing:
        raise BadMessage("missing_field", str(missing.args[0]), sender) from None
    if not isinstance(fields[2], list):
        raise BadMessage("bad_field_type", f"to must be a list of names, got {fields[2]!r}"[:120], sender)
    return Envelope(*fields, in_reply_to=data.get("re"), message_id=message_id)  # checks every field


def _is_version(value: object) -> bool:
    return type(value) is int and value == VERSION  # not True, not 1.0


def _check_fields(version: object, message_id: object, mas: object, sender: object,
                  receivers: object, performative: object, content: object,
                  in_reply_to: object) -> None:
    who = sender if isinstance(sender, str) else None
    if not _is_version(version):
        raise BadMessage("bad_version", f"version {version!r}, this build speaks {VERSION}", who)
    if not isinstance(message_id, str) or not message_id:
        raise BadMessage("bad_field_type", "id must be a non-empty string", who)
    for label, name in (("mas", mas), ("from", sender)):
        if not is_valid_name(name):
            raise BadMessage("bad_field_type", f"{label} must be a name, got {name!r}"[:120], who)
    if (not isinstance(receivers, (list, tuple)) or not receivers
            or not all(is_valid_name(r) for r in receivers)):
        raise BadMessage("bad_field_type", f"to must be a non-empty list of names, got {receivers!r}"[:120], who)
    if not isinstance(performative, str):
        raise BadMessage("bad_field_type", "perf must be a string", who)
    if performative not in PERFORMATIVES:
        raise BadMessage("unknown_performative", repr(performative)[:60], who)
    if not isinstance(content, str):
        raise BadMessage("bad_field_type", "content must be a string (AgentSpeak text)", who)
    if in_reply_to is not None and (not isinstance(in_reply_to, str) or not in_reply_to):
        raise BadMessage("bad_field_type", "re must be a non-empty string when present", who)
