"""The agents' leak-hunting switch (``FAULTMAS_MEMTRACE_DIR``, agents/memory_trace.py): off by default; on, it
writes snapshots and censuses that say what grew, which line allocated it and what holds it."""
from __future__ import annotations

import tracemalloc

from agents.memory_trace import MemoryTrace, agent_holdings, growth, start_from_environment


def test_off_unless_asked(monkeypatch):
    monkeypatch.delenv("FAULTMAS_MEMTRACE_DIR", raising=False)
    assert start_from_environment("robot1") is None
    assert not tracemalloc.is_tracing()


class _Store:
    """What keeps the leak: an object's dict (of untracked objects only, so gc lists the dict through it)."""

    def __init__(self) -> None:
        self.items: dict[int, bytearray] = {}


def _leak(store: _Store) -> None:
    for i in range(2000):
        store.items[i] = bytearray(200)


LEAK_LINE = _leak.__code__.co_firstlineno + 2


def write_snapshots(directory: str) -> None:
    """Two snapshots of robot1, a leak, a last one. Run in a fresh interpreter by the test below: in the test
    session's process gc's and tracemalloc's census would walk the whole session's heap (11 s instead of 3)."""
    from pathlib import Path

    from agentspeak.runtime import LocalRuntime

    runtime = LocalRuntime()
    runtime.add_agent("robot1", "b(1).\n")
    kept = _Store()
    trace = MemoryTrace(Path(directory), "robot1", every=3600, holdings=lambda: agent_holdings(runtime)).start()
    try:
        trace.write()
        trace.write()
        _leak(kept)
        trace.stop()                   # a last snapshot
    finally:
        tracemalloc.stop()


def test_snapshots_say_what_grew_where_and_what_holds_it(tmp_path):
    import json
    import os
    import subprocess
    import sys
    from pathlib import Path

    where = f"test_memory_trace.py:{LEAK_LINE}"
    run = subprocess.run([sys.executable, "-c", "import runpy, sys; runpy.run_path(sys.argv[1])['write_snapshots'](sys.argv[2])",
                          __file__, str(tmp_path)], env=dict(os.environ, FAULTMAS_MEMTRACE_HOLDERS=where),
                         cwd=Path(__file__).resolve().parents[2], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-3000:]
    report = growth(tmp_path, "robot1")
    assert "robot1-001.tracemalloc -> robot1-002.tracemalloc" in report
    top = report.split("top growth by line:\n")[1].splitlines()[0]
    blocks = int(top.split("blocks")[0].split()[-1])
    assert where in top and blocks >= 4000, report     # each bytearray and its buffer (and the dict's growth)
    assert '"beliefs": 1' in report   # each agent's holdings, first and last
    census = json.loads((tmp_path / "robot1-002.census.json").read_text())
    assert census["holders"][where]["objects"] == {"bytearray": 2000}
    assert census["holders"][where]["held_by"] == {"dict": 2000}


def test_the_report_names_a_missing_directory(tmp_path, capsys):
    from agents.memory_trace import main

    assert main([str(tmp_path / "none"), "robot1"]) == 2
    assert "fewer than two snapshots of robot1" in capsys.readouterr().err


def test_the_census_holds_the_simulated_worlds_of_the_process_still(tmp_path, monkeypatch):
    """``gc.get_objects`` beside the simulator's thread failed its camera detector's OpenCV calls (issue 22,
    docs/reliability.md): the census runs while every world of the process stands still."""
    import time

    from agents import memory_trace
    from robot_bridge import Action
    from robot_bridge.sim.bridge import SimBridge

    bridge = SimBridge("robot1")
    bridge.setup()
    world, seen = bridge.world, []
    census = memory_trace.census

    def census_watching_the_world():
        before = world.time
        time.sleep(0.2)
        seen.append((before, world.time))
        return census()

    monkeypatch.setattr(memory_trace, "census", census_watching_the_world)
    try:
        bridge.act(Action("rotate", (30.0,)))             # the world steps flat out
        started = world.time
        deadline = time.monotonic() + 30.0
        while world.time == started and time.monotonic() < deadline:
            time.sleep(0.01)
        MemoryTrace(tmp_path, "robot1", frames=0).write()
        moving = world.time
        time.sleep(0.2)
        assert world.time > moving                        # and it steps again afterwards
    finally:
        bridge.shutdown()
    assert seen and all(before == after for before, after in seen), seen
