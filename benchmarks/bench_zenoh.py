"""Zenoh transport benchmark: raw Zenoh put/subscribe vs faultmas envelopes through the Transport,
between two OS processes on loopback, side by side in one run; plus request/response round trips.

``python -m benchmarks zenoh [--quick]``. Throughput rows: N one-way messages of a payload size,
timed from the first put until the receiving process reports it has counted all N (raw: counted in
the Zenoh callback; Transport: encoded, put, received, decoded, queued and taken from the agent's
inbox by its thread). Round trip: one message out, the answer back (raw ping/pong vs an ``askOne``
envelope answered with ``in_reply_to``). The agent layer adds its ``tell``/``askOne`` rows later.
"""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path
from typing import Any

SIZES = (64, 512, 4096)
REPO = Path(__file__).resolve().parents[1]


def run(quick: bool = False) -> str:
    """Run every measurement (two processes) and return the table."""
    from agents.transport import Envelope, Inbox, ZenohTransport

    count = 5_000 if quick else 50_000
    trips = 300 if quick else 3_000
    mas = f"bench{uuid.uuid4().hex[:6]}"
    with ZenohTransport(mas) as transport:
        inbox = Inbox()
        transport.register("source", inbox)
        child = subprocess.Popen([sys.executable, "-m", "benchmarks.bench_zenoh", "--child", mas,
                                  *transport.endpoints], cwd=REPO, stdin=subprocess.PIPE,
                                 stdout=subprocess.PIPE, text=True, env=dict(os.environ, PYTHONUNBUFFERED="1"))
        try:
            if child.stdout.readline().strip() != "READY" or not transport.wait_for_agents(["sink"], 30):
                raise RuntimeError("benchmark child process did not come up")
            raw = _RawSide(transport.session, mas)
            rows = []
            for size in SIZES:
                raw_rate = raw.throughput(size, count)
                env_rate = _transport_throughput(transport, inbox, Envelope, size, count)
                rows.append((f"one-way {size} B", raw_rate, env_rate))
            raw_rtt = raw.round_trips(200, trips)
            env_rtt = _transport_round_trips(transport, inbox, Envelope, 200, trips)
            raw.close()
            gone = threading.Event()
            transport.on_presence(lambda agent, alive: gone.set() if (agent, alive) == ("sink", False) else None)
            started = time.perf_counter()
            child.kill()  # SIGKILL: how soon do the others know?
            loss = time.perf_counter() - started if gone.wait(30) else float("nan")
        finally:
            child.stdin.close()
            if child.poll() is None:
                child.kill()
            child.wait(30)
    return _table(rows, raw_rtt, env_rtt, count, trips) + f"\nagent process SIGKILLed -> presence loss seen after {loss * 1e3:.1f} ms"


def _table(rows: list[tuple[str, float, float]], raw_rtt: list[float], env_rtt: list[float],
           count: int, trips: int) -> str:
    lines = [f"{'measure (2 processes, loopback)':34} {'raw Zenoh':>14} {'Transport':>14} {'ratio':>7}"]
    for label, raw_rate, env_rate in rows:
        lines.append(f"{label + f' x{count}':34} {raw_rate:>10,.0f} m/s {env_rate:>10,.0f} m/s "
                     f"{env_rate / raw_rate:>6.0%}")
    for name, pick in (("median", lambda v: statistics.median(v)),
                       ("p99", lambda v: sorted(v)[min(len(v) - 1, int(0.99 * len(v)))])):
        raw_us, env_us = pick(raw_rtt) * 1e6, pick(env_rtt) * 1e6
        lines.append(f"{f'round trip 200 B {name} x{trips}':34} {raw_us:>11,.0f} µs {env_us:>11,.0f} µs "
                     f"{raw_us / env_us:>6.0%}")
    lines.append("ratio: Transport / raw for rates, raw / Transport for latencies (100% = no overhead)")
    return "\n".join(lines)


class _RawSide:
    """Plain Zenoh put/subscribe with the same reliability and congestion control as the Transport."""

    def __init__(self, session: Any, mas: str) -> None:
        import zenoh

        self.session, self.prefix = session, f"bench/{mas}"
        self.done = threading.Event()
        self.pong = threading.Event()
        self.subscribers = [session.declare_subscriber(f"{self.prefix}/raw_done", lambda s: self.done.set()),
                            session.declare_subscriber(f"{self.prefix}/pong", lambda s: self.pong.set())]
        options = dict(congestion_control=zenoh.CongestionControl.BLOCK, reliability=zenoh.Reliability.RELIABLE)
        self.data = session.declare_publisher(f"{self.prefix}/raw", **options)
        self.ping = session.declare_publisher(f"{self.prefix}/ping", **options)
        deadline = time.monotonic() + 30
        while not (self.data.matching_status.matching and self.ping.matching_status.matching):
            if time.monotonic() > deadline:
                raise RuntimeError("raw subscribers of the benchmark child not matched")
            time.sleep(0.005)

    def throughput(self, size: int, count: int) -> float:
        payload = b"x" * size
        self.done.clear()
        started = time.perf_counter()
        for _ in range(count):
            self.data.put(payload)
        self.data.put(b"END")
        if not self.done.wait(120):
            raise RuntimeError("raw sink did not report")
        return count / (time.perf_counter() - started)

    def round_trips(self, size: int, trips: int) -> list[float]:
        payload, times = b"x" * size, []
        for _ in range(trips):
            self.pong.clear()
            started = time.perf_counter()
            self.ping.put(payload)
            if not self.pong.wait(10):
                raise RuntimeError("raw pong missing")
            times.append(time.perf_counter() - started)
        return times

    def close(self) -> None:
        for entity in (*self.subscribers, self.data, self.ping):
            entity.undeclare()


def _transport_throughput(transport: Any, inbox: Any, envelope: Any, size: int, count: int) -> float:
    content = "x" * size
    started = time.perf_counter()
    for _ in range(count):
        transport.send(envelope(transport.mas, "source", ("sink",), "tell", content))
    transport.send(envelope(transport.mas, "source", ("sink",), "tell", "end"))
    answer = inbox.get(timeout=120)
    elapsed = time.perf_counter() - started
    if answer is None or answer.content != f"done({count})":
        raise RuntimeError(f"sink answered {answer!r}, expected done({count})")
    return count / elapsed


def _transport_round_trips(transport: Any, inbox: Any, envelope: Any, size: int, trips: int) -> list[float]:
    content, times = "x" * size, []
    for _ in range(trips):
        started = time.perf_counter()
        question = envelope(transport.mas, "source", ("sink",), "askOne", content)
        transport.send(question)
        answer = inbox.get(timeout=10)
        times.append(time.perf_counter() - started)
        if answer is None or answer.in_reply_to != question.message_id:
            raise RuntimeError(f"bad answer {answer!r}")
    return times


def _child(mas: str, endpoints: list[str]) -> None:
    """The receiving process: a raw counter and ping echo, and a Transport agent ``sink`` whose thread
    counts tells (answering ``done(N)`` after ``end``) and answers each askOne at once."""
    import zenoh

    from agents.transport import Inbox, ZenohOptions, ZenohTransport

    with ZenohTransport(mas, ZenohOptions(connect=tuple(endpoints))) as transport:
        session, prefix = transport.session, f"bench/{mas}"
        counted = [0]

        def on_raw(sample: Any) -> None:
            if sample.payload.to_bytes() == b"END":
                session.put(f"{prefix}/raw_done", json.dumps(counted[0]))
                counted[0] = 0
            else:
                counted[0] += 1

        pong = session.declare_publisher(f"{prefix}/pong", congestion_control=zenoh.CongestionControl.BLOCK)
        keep = [session.declare_subscriber(f"{prefix}/raw", on_raw),
                session.declare_subscriber(f"{prefix}/ping", lambda s: pong.put(s.payload.to_bytes()))]
        inbox = Inbox()
        transport.register("sink", inbox)
        stop = threading.Event()
        threading.Thread(target=lambda: (sys.stdin.read(), stop.set()), daemon=True).start()
        print("READY", flush=True)
        tells = 0
        while not stop.is_set():
            first = inbox.get(timeout=0.1)  # then take the whole burst, as an agent's mail check does
            for message in ([first, *inbox.drain()] if first is not None else ()):
                if message.performative == "askOne":
                    transport.send(message.reply("tell", message.content, sender="sink"))
                elif message.content == "end":
                    transport.send(message.reply("tell", f"done({tells})", sender="sink"))
                    tells = 0
                else:
                    tells += 1
        del keep


if __name__ == "__main__":
    if len(sys.argv) >= 3 and sys.argv[1] == "--child":
        _child(sys.argv[2], sys.argv[3:])
    else:
        print(run(quick="--quick" in sys.argv))
