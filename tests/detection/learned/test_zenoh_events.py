"""The learned detector's Zenoh tap on real Zenoh sessions (loopback TCP, no multicast): JSON Lines decoded
generically (a batch gives one event per envelope), the sender and receivers read from the values
themselves, a bad payload dropped and counted, and the recorder's columns made from what was seen."""
from __future__ import annotations

import json
import socket
import time

import numpy as np
import pytest

from robot_bridge.ros2.runtime import wait_for

zenoh = pytest.importorskip("zenoh")

INBOX = "faultmas/m/agent/bob/inbox"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def envelope(i: int, content: str, **extra) -> bytes:
    return json.dumps({"v": 1, "id": f"x.{i}", "mas": "m", "from": "alice", "to": ["bob"], "perf": "tell",
                       "content": content, **extra}, separators=(",", ":")).encode()


def test_envelopes_on_a_real_session_become_events_of_their_sender_and_receiver(tmp_path):
    from detection.learned.record import RunRecorder
    from detection.learned.zenoh_events import ZenohEventTap
    from detection.taps.zenoh import zenoh_config

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    publisher = zenoh.open(zenoh_config(listen=[endpoint]))
    recorder = RunRecorder({})
    tap = ZenohEventTap(recorder.on_json, connect=[endpoint])
    try:
        probe = publisher.declare_publisher(INBOX)
        assert wait_for(lambda: probe.matching_status.matching, 10.0), "the tap never subscribed"
        publisher.put(INBOX, envelope(1, "position(3,4)"))
        publisher.put(INBOX, envelope(2, "a") + b"\n" + envelope(3, "bb", re="x.0"))       # a batch of two
        publisher.put(INBOX, b"{not json")
        publisher.put("faultmas/m/status/alice", b'{"agent":"alice","busy":true,"sent":3,"received":1}')
        assert wait_for(lambda: tap.received == 4 and tap.dropped, 10.0), (tap.received, tap.dropped)
    finally:
        tap.close()
        publisher.close()
    assert tap.dropped == {INBOX: 1}
    components = tap.channels.components(["alice", "bob", "carol"])
    assert components["alice_agent"].outputs == [INBOX, "faultmas/m/status/alice"]
    assert components["bob_agent"].inputs == [INBOX] and components["bob_agent"].outputs == []
    assert "carol_agent" not in components                   # nothing of hers seen: no component
    recorder.ticks = [time.time()]
    counts = recorder.save(tmp_path / "run.npz")
    assert counts == {INBOX: 3, "faultmas/m/status/alice": 1}
    columns = recorder.columns[INBOX]
    assert columns == ["size", "content#len", "from#len", "id#len", "mas#len", "perf#len", "re#len", "to#len", "v"]
    with np.load(tmp_path / "run.npz") as arrays:
        x = arrays[f"events/{INBOX}/x"]
    assert x[:, columns.index("content#len")].tolist() == [13, 1, 2]
    assert x[:, columns.index("re#len")].tolist() == [0, 0, 3]               # absent in the first two: 0
    assert x[0, 0] == len(envelope(1, "position(3,4)"))                      # the size of its own line
    assert recorder.columns["faultmas/m/status/alice"] == ["size", "agent#len", "busy", "received", "sent"]
