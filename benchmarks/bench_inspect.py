"""``python -m benchmarks inspect``: what the inspector costs an agent (issue 27: unchanged ±3 % when
nobody inspects; the cost when someone watches), and how fast the page's team list learns of a death.

One agent counts to N with one goal per step, over a real Zenoh transport in this process (the way
``faultmas agent run`` runs it), in four set-ups run interleaved, each several times (the median):
without the inspector's publisher; with it but nobody looking (what every agent of a MAS pays);
with a viewer asking for the team summaries twice a second (the page open on another agent); with a
viewer watching this agent's change stream (the page open on it). Then a ``faultmas agent run`` child
is SIGKILLed and the time until a ``TeamHub`` marks it gone is measured (the page shows it at its next
event, at most 1/``MAX_RATE`` s later).
"""
from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

COUNT = """
!count(0).
+!count(N) : N < {n} <- !count(N + 1).
+!count(N) <- .stopMAS.
"""
SETUPS = ("no publisher", "publisher, nobody looks", "team list open (summaries 2/s)", "agent watched (stream)")


def _one(setup: str, n: int) -> tuple[float, float]:
    """Wall and process CPU seconds for one agent to count to ``n`` in ``setup``."""
    import zenoh

    from agents.inspector import keys
    from agents.inspector.publisher import MindPublisher
    from agents.transport import ZenohOptions, ZenohTransport, loopback_endpoint
    from agents.transport.config import build_config
    from agents.zenoh_arch import TransportBridge
    from agentspeak.runtime import LocalRuntime

    runtime = LocalRuntime()
    runtime.add_agent("counter", COUNT.format(n=n), "count.asl")
    transport = ZenohTransport("bench", ZenohOptions(listen=(loopback_endpoint(),))).open()
    bridge = TransportBridge(runtime, transport, declared=["counter"]).attach()
    publisher = viewer = None
    stop = threading.Event()
    try:
        if setup != SETUPS[0]:
            publisher = MindPublisher(transport, runtime, bridge).start()
        if setup in SETUPS[2:]:
            viewer = zenoh.open(build_config(ZenohOptions(connect=tuple(transport.endpoints))))
            time.sleep(0.3)
        if setup == SETUPS[2]:
            def ask() -> None:
                while not stop.wait(0.5):
                    list(viewer.get(keys.state_pattern("bench") + "?summary", timeout=2))
            threading.Thread(target=ask, daemon=True).start()
        elif setup == SETUPS[3]:
            viewer.declare_subscriber(keys.stream_key("bench", "counter"), lambda sample: None)
            time.sleep(0.3)
        started, cpu = time.perf_counter(), time.process_time()
        why = bridge.run(timeout=300)
        elapsed, cpu = time.perf_counter() - started, time.process_time() - cpu
        if why != "stopped":
            raise RuntimeError(f"the counter did not finish ({why})")
        return elapsed, cpu
    finally:
        stop.set()
        if publisher is not None:
            publisher.close()
        if viewer is not None:
            viewer.close()
        transport.close()


def _put_cost(repeats: int) -> tuple[float, int, int]:
    """CPU seconds of one put of the stream (the mind read and encoded) for faulty.asl's agent, with its
    plan library and initial beliefs; and its size in bytes and number of beliefs."""
    from importlib import resources

    from agents.inspector import snapshot
    from agents.inspector.publisher import _encode
    from agentspeak.runtime import LocalRuntime

    path = resources.files("plans").joinpath("faulty.asl")
    runtime = LocalRuntime()
    agent = runtime.add_agent("faulty", path.read_text(), str(path))
    started = time.process_time()
    for _ in range(repeats):
        payload = _encode(snapshot.mind(agent))
    return (time.process_time() - started) / repeats, len(payload), len(agent.bb)


def _death_latency(trials: int) -> list[float]:
    """Seconds from SIGKILL of an agent process to a TeamHub marking it gone."""
    import zenoh

    from agents.inspector.hub import TeamHub
    from agents.transport import ZenohOptions, loopback_endpoint
    from agents.transport.config import build_config

    endpoint = loopback_endpoint()
    session = zenoh.open(build_config(ZenohOptions(listen=(endpoint,))))
    hub = TeamHub(session, "benchdeath").start()
    latencies = []
    with tempfile.TemporaryDirectory() as tmp:
        source = Path(tmp) / "idle.asl"
        source.write_text("!wait.\n+!wait <- .wait(600000).\n")
        try:
            for i in range(trials):
                name = f"victim{i}"
                child = subprocess.Popen([sys.executable, "-m", "agents", "agent", "run", str(source), "--name", name,
                                          "--mas", "benchdeath", "--connect", endpoint],
                                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                deadline = time.monotonic() + 60
                while not hub.agents.get(name, {}).get("alive") and time.monotonic() < deadline:
                    time.sleep(0.01)
                killed = time.monotonic()
                child.kill()
                child.wait()
                while hub.agents.get(name, {}).get("alive") and time.monotonic() < killed + 10:
                    time.sleep(0.001)
                latencies.append(time.monotonic() - killed)
        finally:
            hub.close()
            session.close()
    return latencies


def run(quick: bool = False) -> str:
    from agents.inspector.web import MAX_RATE

    n = 50_000 if quick else 300_000
    rounds = 3 if quick else 7
    times: dict[str, list[float]] = {s: [] for s in SETUPS}
    cpus: dict[str, list[float]] = {s: [] for s in SETUPS}
    for _ in range(rounds):
        for setup in SETUPS:   # interleaved, so load changes on the machine hit every set-up alike
            wall, cpu = _one(setup, n)
            times[setup].append(wall)
            cpus[setup].append(cpu)
    base = statistics.median(times[SETUPS[0]])
    base_cpu = statistics.median(cpus[SETUPS[0]])
    lines = [f"{'one agent counting to ' + format(n, ',') + ' (median of ' + str(rounds) + ')':40} {'goals/s':>9} "
             f"{'vs none':>8} {'spread':>7} {'CPU µs/goal':>12} {'vs none':>8}"]
    for setup in SETUPS:
        median, cpu = statistics.median(times[setup]), statistics.median(cpus[setup])
        spread = (max(times[setup]) - min(times[setup])) / median
        lines.append(f"{setup:40} {n / median:>9,.0f} {base / median - 1:>+8.1%} {spread:>7.0%} "
                     f"{cpu / n * 1e6:>12.2f} {cpu / base_cpu - 1:>+8.1%}")
    put, size, beliefs = _put_cost(200 if quick else 1000)
    from agents.inspector.publisher import PERIOD
    lines.append(f"one put of faulty.asl's mind ({beliefs} beliefs, {size:,} B): {put * 1e6:.0f} µs of CPU; at most "
                 f"{1 / PERIOD:.0f} puts/s while watched and cycling = {put / PERIOD:.1%} of one core")
    deaths = _death_latency(3 if quick else 5)
    lines.append(f"a killed agent marked gone by the hub after {statistics.median(deaths) * 1000:.0f} ms (median, "
                 f"max {max(deaths) * 1000:.0f} ms); the page shows it within {1000 / MAX_RATE:.0f} ms more")
    lines.append("target: 'publisher, nobody looks' within ±3 % of 'no publisher' (CPU per goal: wall rates on a "
                 "shared machine vary more than that between identical runs, see spread = (max - min) / median)")
    return "\n".join(lines)
