"""An agent whose environment has a clock of its own (a simulator's) counts its waits and timeouts in it
(``AgentArch.environment_clock``); without one, wall time as in Jason (the other .wait tests)."""
from __future__ import annotations

import threading
import time

from agentspeak.runtime import LocalArch, LocalRuntime


class ManualClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


class ClockedArch(LocalArch):
    def __init__(self, runtime: LocalRuntime, clock: ManualClock) -> None:
        super().__init__(runtime)
        self._clock = clock

    def environment_clock(self):
        return self._clock


SOURCE = """
!start.
+!start <- .wait(1000); .print(waited); .wait({+never}, 2000, E); .print(elapsed(E)); .stopMAS.
"""


def wait_for(lines: list[str], count: int, seconds: float = 20.0) -> None:
    deadline = time.monotonic() + seconds
    while len(lines) < count and time.monotonic() < deadline:
        time.sleep(0.01)


def test_waits_and_elapsed_times_count_in_the_environments_clock_not_in_wall_time():
    lines: list[str] = []
    clock = ManualClock()
    runtime = LocalRuntime(printer=lambda name, text: lines.append(text))
    runtime.add_agent("ag", SOURCE, arch=ClockedArch(runtime, clock))
    loop = threading.Thread(target=runtime.run, kwargs={"timeout": 60, "stop_when_idle": False}, daemon=True)
    loop.start()
    try:
        time.sleep(1.5)                  # longer than the wait, in wall time: the environment's clock stood
        assert lines == []
        clock.now += 1.0
        wait_for(lines, 1)
        assert lines == ["waited"]
        clock.now += 1.5                 # the timeout (2 s) is not reached yet
        time.sleep(0.3)
        assert lines == ["waited"]
        clock.now += 1.0
        wait_for(lines, 2)
        assert lines == ["waited", "elapsed(2500)"]
    finally:
        runtime.stop()
        loop.join(10)
    assert not loop.is_alive()
