"""What a tap hands to the observers: one message on one channel at one receive time.

A tap may hand the raw bytes (a ROS 2 raw subscription, a bag) with a decoder that is only called when
an observer needs a field, or an already decoded object (a simulator driving observers in-process, a
Zenoh payload). Fields are read by a dotted path (``twist.twist.angular.z``) on attributes or mapping
keys, so rclpy messages, rosbags dataclasses and dicts all work.
"""
from __future__ import annotations

from typing import Any, Callable


class MessageError(ValueError):
    """A message that cannot be decoded or lacks a field an observer needs."""


class Message:
    __slots__ = ("channel", "t_ns", "raw", "_data", "_decode")

    def __init__(self, channel: str, t_ns: int, data: Any = None, raw: bytes | None = None,
                 decode: Callable[[bytes], Any] | None = None) -> None:
        self.channel = channel
        self.t_ns = t_ns
        self.raw = raw
        self._data = data
        self._decode = decode

    @property
    def time(self) -> float:
        return self.t_ns / 1e9

    @property
    def data(self) -> Any:
        """The decoded message (decoded once, on first use)."""
        if self._data is None and self.raw is not None:
            if self._decode is None:
                raise MessageError(f"{self.channel}: no decoder for the raw message")
            try:
                self._data = self._decode(self.raw)
            except Exception as exc:   # a decoder's own errors vary by library: name the message instead
                raise MessageError(f"{self.channel}: cannot decode message: {exc}") from None
        return self._data

    def field(self, path: tuple[str, ...]) -> float:
        """The number at a dotted path, e.g. ``("angular_velocity", "z")``."""
        value = self.data
        for part in path:
            try:
                value = value[part] if isinstance(value, dict) else getattr(value, part)
            except (KeyError, AttributeError, TypeError):
                raise MessageError(f"{self.channel}: message has no field {'.'.join(path)!r}") from None
        try:
            return float(value)
        except (TypeError, ValueError):
            raise MessageError(f"{self.channel}: field {'.'.join(path)!r} is not a number: {value!r}") from None
