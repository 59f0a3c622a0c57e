"""Taking serialized ROS 2 messages with one copy, or only their first bytes: rcl's C API via ctypes.

Why not rclpy's raw take: it allocates a new buffer for every message, the middleware copies the
message into it, then rclpy copies it again into Python bytes. For a 900 kB camera image that is
~1.4 ms of CPU per image (measured on the shared machine; ~0.3 ms with the buffer below), the
largest part of what the learned detector spent watching a team with cameras. Here one buffer is
kept from one take to the next (the middleware's copy into it is the only one of the whole message)
and a consumer that needs only a message's first bytes — the learned detector reads an image's
header, sizes and pixel count, never its pixels — gets those (``MessageHead``), not the rest.

``rcl_take_serialized_message`` is rcl's public, stable C function behind rclpy's own raw take; the
structures passed are ``rcutils_uint8_array_t`` and the two leading timestamps of
``rmw_message_info_t`` (a larger zeroed block is passed for the rest). ``Taker.create()`` returns
None where the library cannot be used, and the reader then takes through rclpy as before.
"""
from __future__ import annotations

import ctypes
import logging
import time

log = logging.getLogger("faultmas.detection")

HEAD_BYTES = 65536
"""What a consumer that needs only a message's first bytes asks for (``TopicReader.subscribe(head=)``):
far more than any header with its strings, far less than an image."""

RCL_RET_OK = 0
RCL_RET_SUBSCRIPTION_TAKE_FAILED = 401      # nothing to take: not an error


class MessageHead(bytes):
    """The first bytes of a serialized message of ``size`` bytes (the rest was not copied)."""

    size: int

    def __new__(cls, head: bytes, size: int) -> "MessageHead":
        self = super().__new__(cls, head)
        self.size = size
        return self


class _Allocator(ctypes.Structure):
    _fields_ = [("allocate", ctypes.c_void_p), ("deallocate", ctypes.c_void_p), ("reallocate", ctypes.c_void_p),
                ("zero_allocate", ctypes.c_void_p), ("state", ctypes.c_void_p)]


class _Uint8Array(ctypes.Structure):                 # rcutils_uint8_array_t == rcl_serialized_message_t
    _fields_ = [("buffer", ctypes.c_void_p), ("buffer_length", ctypes.c_size_t),
                ("buffer_capacity", ctypes.c_size_t), ("allocator", _Allocator)]


class _MessageInfo(ctypes.Structure):                # rmw_message_info_t: its timestamps, room for the rest
    _fields_ = [("source_timestamp", ctypes.c_int64), ("received_timestamp", ctypes.c_int64),
                ("rest", ctypes.c_uint8 * 256)]


def _libraries():
    """rcl and rcutils as rclpy loaded them (found by their sonames once rclpy's extension is loaded)."""
    from rclpy.impl.implementation_singleton import rclpy_implementation  # noqa: F401  (loads librcl)

    rcl, rcutils = ctypes.CDLL("librcl.so"), ctypes.CDLL("librcutils.so")
    take = rcl.rcl_take_serialized_message   # (subscription, buffer, info, allocation): given as ctypes
    take.restype = ctypes.c_int                 # objects, no argtypes (their conversion doubles a call's cost)
    rcutils.rcutils_get_default_allocator.restype = _Allocator
    rcutils.rcutils_uint8_array_init.argtypes = [ctypes.POINTER(_Uint8Array), ctypes.c_size_t,
                                                 ctypes.POINTER(_Allocator)]
    rcutils.rcutils_uint8_array_init.restype = ctypes.c_int
    rcutils.rcutils_uint8_array_fini.argtypes = [ctypes.POINTER(_Uint8Array)]
    rcutils.rcutils_uint8_array_fini.restype = ctypes.c_int
    return take, rcutils


class Taker:
    """Takes one subscription's next message into a buffer of its own, kept between takes (so one
    thread per ``Taker``: the reader's)."""

    def __init__(self, take, rcutils, capacity: int = 4096) -> None:
        self._take, self._rcutils = take, rcutils
        self._buffer = _Uint8Array()
        allocator = rcutils.rcutils_get_default_allocator()
        if rcutils.rcutils_uint8_array_init(ctypes.byref(self._buffer), capacity, ctypes.byref(allocator)) != 0:
            raise MemoryError("rcutils_uint8_array_init failed")
        self._info = _MessageInfo()
        self._buffer_ref, self._info_ref = ctypes.byref(self._buffer), ctypes.byref(self._info)
        self._view_at, self._view = None, memoryview(b"")      # the buffer's bytes, seen without a copy

    @classmethod
    def create(cls) -> "Taker | None":
        """A taker, or None (logged) where rcl's library cannot be loaded this way."""
        try:
            return cls(*_libraries())
        except (OSError, AttributeError, MemoryError, ImportError) as exc:
            log.info("ROS 2 reader: taking through rclpy (rcl's C API not usable: %s)", exc)
            return None

    def drain(self, subscription_pointer: int, topic: str, head: int | None, out: list) -> None:
        """Append every message waiting on the ``rcl_subscription_t`` at ``subscription_pointer`` to ``out``
        as (receive time in ns, ``topic``, its bytes). With ``head``, a message longer than ``head`` bytes
        comes as a ``MessageHead`` of its first ``head`` bytes. The caller holds the subscription's handle
        (``with sub.handle:``) so that it cannot be destroyed meanwhile. One call per subscription, the
        loop inside: a Python call per message would cost more than rclpy's own take."""
        take, buffer, info = self._take, self._buffer, self._info
        subscription, buffer_ref, info_ref = ctypes.c_void_p(subscription_pointer), self._buffer_ref, self._info_ref
        while True:
            ret = take(subscription, buffer_ref, info_ref, None)
            if ret != RCL_RET_OK:
                if ret == RCL_RET_SUBSCRIPTION_TAKE_FAILED:
                    return
                raise RuntimeError(f"rcl_take_serialized_message failed ({ret})")
            size = buffer.buffer_length
            if buffer.buffer != self._view_at or buffer.buffer_capacity != len(self._view):
                self._view_at = buffer.buffer       # the middleware grew the buffer: view it anew
                self._view = memoryview((ctypes.c_char * buffer.buffer_capacity).from_address(buffer.buffer)).cast("B")
            if head is not None and size > head:
                data = MessageHead(self._view[:head], size)
            else:
                data = bytes(self._view[:size])     # cheaper than ctypes.string_at
            out.append((info.received_timestamp or time.time_ns(), topic, data))

    def close(self) -> None:
        """Free the buffer (idempotent)."""
        if self._buffer.buffer:
            self._view.release()
            self._view_at, self._view = None, memoryview(b"")
            self._rcutils.rcutils_uint8_array_fini(self._buffer_ref)
