"""Replay of a recorded rosbag2 (MCAP or sqlite3) through the observers, and recording one live.

``replay`` yields the ``Message`` s of the topics a configuration reads, in time order, with the bag's
receive times; raw bytes are decoded only if an observer reads a field. ``BagRecorder`` writes what a
live tap received (with the same receive times, the taps' own channels and the start of the run), so
replaying it gives exactly the observations of the live run.
"""
from __future__ import annotations

from pathlib import Path
from typing import Iterable, Iterator

from agentspeak.errors import SourceError
from detection.message import Message
from detection.taps import codec

STORAGES = ("mcap", "sqlite3")


class BagError(SourceError):
    """A bag that does not exist, cannot be read, or lacks what the configuration needs."""


def start_time_ns(path: str | Path) -> int | None:
    """The start of the live run recorded in the bag (None: not recorded by a tap)."""
    return _marker_time_ns(path, codec.START_TOPIC)


def stop_time_ns(path: str | Path) -> int | None:
    """How far the live run's clock went (None: not recorded, e.g. a bag of another tool)."""
    return _marker_time_ns(path, codec.STOP_TOPIC)


def _messages(reader, conns: list):
    """The messages of ``conns`` only: none when it is empty (rosbags reads every connection when given none)."""
    return reader.messages(connections=conns) if conns else iter(())


def _marker_time_ns(path: str | Path, topic: str) -> int | None:
    reader = _open(path)
    try:
        conns = [c for c in reader.connections if c.topic == topic]
        for _conn, t_ns, _raw in _messages(reader, conns):
            return t_ns
        return None
    finally:
        reader.close()


def first_tap_data(path: str | Path, channel: str):
    """The data of the first message on a tap channel (``@learned/components``); None when there is none."""
    reader = _open(path)
    try:
        conns = [c for c in reader.connections if c.topic == codec.tap_topic(channel)]
        for _conn, _t_ns, raw in _messages(reader, conns):
            return codec.decode_tap_data(channel, raw)
        return None
    finally:
        reader.close()


def topic_types(path: str | Path) -> dict[str, str]:
    """The bag's topics and their message types (the taps' own channels left out)."""
    reader = _open(path)
    try:
        return {c.topic: c.msgtype for c in reader.connections if not c.topic.startswith(codec.TAP_PREFIX)}
    finally:
        reader.close()


def _open(path: str | Path):
    from rosbags.rosbag2 import Reader

    path = Path(path)
    if not path.exists():
        raise BagError("no such bag", file=str(path))
    try:
        reader = Reader(path)
        reader.open()
    except Exception as exc:      # rosbags raises its own errors, and OSError / yaml errors on broken files
        raise BagError(f"cannot read this bag: {exc}", file=str(path)) from None
    return reader


def replay(path: str | Path, topics: Iterable[str]) -> Iterator[Message]:
    """The bag's messages on ``topics`` and on the taps' own channels, in receive-time order."""
    wanted = set(topics)
    reader = _open(path)
    try:
        conns, decoders = [], {}
        for conn in reader.connections:
            channel = codec.tap_channel(conn.topic)
            if channel is not None:
                conns.append(conn)
            elif conn.topic in wanted:
                conns.append(conn)
                decoders[conn.id] = _decoder(conn, path)
        missing = wanted - {c.topic for c in reader.connections}
        if missing:
            import logging
            logging.getLogger("faultmas.detection").warning(
                "%s: no messages on %s in this bag", path, ", ".join(sorted(missing)))
        try:
            for conn, t_ns, raw in _messages(reader, conns):
                channel = codec.tap_channel(conn.topic)
                if channel is not None:
                    yield Message(channel, t_ns, codec.decode_tap_data(channel, raw))
                else:
                    yield Message(conn.topic, t_ns, raw=bytes(raw), decode=decoders[conn.id])
        except BagError:
            raise
        except Exception as exc:      # a truncated or corrupt chunk
            raise BagError(f"bag is truncated or corrupt: {exc}", file=str(path)) from None
    finally:
        reader.close()


def _decoder(conn, path):
    try:
        return codec.decoder(conn.msgtype)
    except codec.UnknownType:
        msgdef = getattr(conn, "msgdef", None)
        if msgdef is not None and msgdef.data:
            try:
                codec.register_definition(conn.msgtype, msgdef.data, getattr(msgdef, "format", "msg"))
                return codec.decoder(conn.msgtype)
            except Exception:
                pass
        raise BagError(f"topic {conn.topic}: unknown message type {conn.msgtype!r} and no usable definition "
                       "in the bag", file=str(path)) from None


class BagRecorder:
    """Writes raw messages with their receive times to a new rosbag2 (MCAP by default)."""

    def __init__(self, path: str | Path, storage: str = "mcap") -> None:
        from rosbags.rosbag2 import StoragePlugin, Writer

        if storage not in STORAGES:
            raise ValueError(f"storage is one of {', '.join(STORAGES)}")
        self.path = Path(path)
        if self.path.exists():
            raise BagError("the bag already exists; choose a new path", file=str(self.path))
        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        self._writer = Writer(self.path, version=9, storage_plugin=plugin)
        self._writer.open()
        self._connections: dict[str, object] = {}

    def _connection(self, topic: str, msgtype: str):
        conn = self._connections.get(topic)
        if conn is None:
            conn = self._writer.add_connection(topic, msgtype, typestore=codec.typestore())
            self._connections[topic] = conn
        return conn

    def start(self, t_ns: int) -> None:
        self._writer.write(self._connection(codec.START_TOPIC, codec.STRING), t_ns, codec.encode_string("start"))

    def stop(self, t_ns: int) -> None:
        """The live clock's last evaluation: the timer may have evaluated after the last message (a rate
        that recovered, a timeout), and a replay must run its clock that far too to see the same."""
        self._writer.write(self._connection(codec.STOP_TOPIC, codec.STRING), t_ns, codec.encode_string("stop"))

    def write(self, msg: Message, msgtype: str | None = None) -> None:
        if msg.channel.startswith("@"):
            raw = codec.encode_tap_data(msg.channel, msg.data)
            self._writer.write(self._connection(codec.tap_topic(msg.channel), codec.STRING), msg.t_ns, raw)
        else:
            self._writer.write(self._connection(msg.channel, msgtype), msg.t_ns, msg.raw)

    def close(self) -> None:
        self._writer.close()
