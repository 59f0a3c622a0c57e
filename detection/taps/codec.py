"""Decoding ROS 2 messages, and how the taps' own channels are stored in a bag.

One decoder for live and replayed messages (rosbags' CDR deserializer and its Jazzy type store), so
a field read online and from a bag is the same number. The channels a tap makes itself (``@graph``,
``@resource/NODE``) and the start of a live run are recorded as ``std_msgs/msg/String`` JSON on topics
under ``/observers/tap/``, so a replay sees exactly what the live observers saw.
"""
from __future__ import annotations

import json
from functools import lru_cache
from typing import Any, Callable

TAP_PREFIX = "/observers/tap/"
START_TOPIC = TAP_PREFIX + "start"
STOP_TOPIC = TAP_PREFIX + "stop"      # how far the live clock went (evaluations after the last message)
STRING = "std_msgs/msg/String"


class UnknownType(ValueError):
    """A message type no type store knows."""


@lru_cache(maxsize=1)
def typestore():
    from rosbags.typesys import Stores, get_typestore
    return get_typestore(Stores.ROS2_JAZZY)


def decoder(msgtype: str) -> Callable[[bytes], Any]:
    """A function from raw CDR bytes to a decoded message of ``msgtype`` (``sensor_msgs/msg/Imu``)."""
    store = typestore()
    if msgtype not in store.types:
        raise UnknownType(f"unknown message type {msgtype!r} (not a ROS 2 Jazzy type this tap can decode)")
    return lambda raw: store.deserialize_cdr(raw, msgtype)


def register_definition(msgtype: str, definition: str, encoding: str = "msg") -> None:
    """Teach the type store a type defined in a bag (custom messages)."""
    from rosbags.typesys import get_types_from_idl, get_types_from_msg
    types = get_types_from_idl(definition) if encoding == "idl" else get_types_from_msg(definition, msgtype)
    typestore().register(types)


def tap_topic(channel: str) -> str:
    """``@graph`` -> ``/observers/tap/graph``; ``@resource/amcl`` -> ``/observers/tap/resource/amcl``."""
    return TAP_PREFIX + channel[1:]


def tap_channel(topic: str) -> str | None:
    """The inverse of ``tap_topic``; None for ordinary topics and for the start and stop markers."""
    if not topic.startswith(TAP_PREFIX) or topic in (START_TOPIC, STOP_TOPIC):
        return None
    return "@" + topic[len(TAP_PREFIX):]


def encode_tap_data(channel: str, data: Any) -> bytes:
    """A tap channel's data as the CDR of a ``std_msgs/String`` holding JSON."""
    payload = sorted(data) if isinstance(data, (set, frozenset)) else data
    store = typestore()
    return bytes(store.serialize_cdr(store.types[STRING](data=json.dumps(payload)), STRING))


def decode_tap_data(channel: str, raw: bytes) -> Any:
    text = typestore().deserialize_cdr(raw, STRING).data
    data = json.loads(text)
    return frozenset(data) if channel == "@graph" else data


def encode_string(text: str) -> bytes:
    store = typestore()
    return bytes(store.serialize_cdr(store.types[STRING](data=text), STRING))
