"""The learned detector's Zenoh tap on real Zenoh sessions (loopback TCP, no multicast): JSON Lines decoded
generically (a batch gives one event per envelope), the sender and receivers read from the values
themselves, a bad payload dropped and counted, and the recorder's columns made from what was seen."""
from __future__ import annotations

import json
import os
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


def test_a_key_gives_the_same_features_online_as_recorded(tmp_path):
    """The online path (``ZenohFeed`` → the observer's buffers) and the recorded one (``RunRecorder`` →
    the data set's features) see the same events of one session and compute the same numbers."""
    from detection.learned.features import ChannelBuffer, window_features
    from detection.learned.record import RunRecorder, event_times
    from detection.learned.zenoh_events import ZenohEventTap, ZenohFeed
    from detection.taps.zenoh import ZenohKeys, zenoh_config

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    publisher = zenoh.open(zenoh_config(listen=[endpoint]))
    keys = ZenohKeys(connect=[endpoint])                       # one session, two consumers
    recorder = RunRecorder({})
    columns = ["size", "content#len", "from#len", "id#len", "mas#len", "perf#len", "to#len", "v"]
    buffer = ChannelBuffer(len(columns))
    tap = ZenohEventTap(recorder.on_json, keys=keys)
    feed = ZenohFeed({INBOX: columns, "faultmas/m/never": ["size"]}, lambda t, key, v: buffer.add(t, v), keys=keys)
    try:
        probe = publisher.declare_publisher(INBOX)
        assert wait_for(lambda: probe.matching_status.matching, 10.0), "the taps never subscribed"
        for i in range(6):
            publisher.put(INBOX, envelope(i, "x" * (i * 7)))
            time.sleep(0.3)
        assert wait_for(lambda: tap.received == 6, 10.0), tap.received
        time.sleep(0.5)
        assert feed.drain() == 6
    finally:
        feed.close()
        tap.close()
        keys.close()
        publisher.close()
    recorder.ticks = [time.time()]
    recorder.save(tmp_path / "run.npz")
    assert recorder.columns[INBOX] == columns
    with np.load(tmp_path / "run.npz") as arrays:
        times, values = event_times(arrays, INBOX), arrays[f"events/{INBOX}/x"].astype(np.float64)
    tick = float(times[-1]) + 0.25
    offline = window_features(times, values, np.array([tick]))[0]
    online = buffer.features(tick)
    assert offline[columns.index("content#len")] > 0                       # the 2.5 s window's mean
    np.testing.assert_allclose(online, offline, rtol=0, atol=1e-6)


def test_an_agents_process_is_found_by_its_command_line_and_never_guessed():
    import subprocess
    import sys

    from detection.learned.zenoh_events import agent_processes

    def sleeper(*argv: str) -> subprocess.Popen:          # a process with an agent's command line
        return subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)", *argv])
    me, mas = f"probe{os.getpid()}", f"mas{os.getpid()}"    # names no other run on this host uses
    procs = [sleeper("agent", "run", "a.asl", "--name", me, "--mas", mas),
             sleeper("agent", "run", "a.asl", "--name", me, "--mas", mas + "x"),
             sleeper("agent", "list", "--name", me + "h")]
    try:
        assert wait_for(lambda: len(agent_processes([me], mas)) == 1, 10.0)
        assert agent_processes([me], mas)[f"{me}_agent"].pid == procs[0].pid
        assert agent_processes([me + "h"]) == {}                              # not 'agent run'
        with pytest.raises(ValueError, match="several processes look like the same agent"):
            agent_processes([me])                                             # two MAS, none named
        procs.append(sleeper("agent", "run", "a.asl", "--name", me, "--mas", mas, "--connect", "tcp/127.0.0.1:9"))
        assert wait_for(lambda: len(agent_processes([me], mas, ["tcp/127.0.0.1:9"])) == 1, 10.0)
        assert agent_processes([me], mas, ["tcp/127.0.0.1:9"])[f"{me}_agent"].pid == procs[-1].pid
    finally:
        for p in procs:
            p.kill()
