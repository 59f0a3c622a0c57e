"""Performance bugs switched on inside a running node for a time slice, for the learned detector's data.

Enabled only by the environment: ``FAULTMAS_PERFBUGS=/path/schedule.json`` makes :func:`run_node`
(the shared ``main`` of every node) call :func:`install_from_env` on the node it built. Nothing in a
node's own code changes: the hook wraps the node's subscription and timer callbacks and its publishers'
``publish`` (rclpy keeps them as plain attributes), and runs the resource-eating bugs in a daemon
thread of the node's process. Without the variable no wrapper is installed, so a normal run pays nothing.

The schedule is the ground truth (wall-clock times, seconds); the hook re-reads it whenever it changes::

    {"faults": [{"component": "faulty_kobuki_sim", "kind": "memory_leak", "start": 1764081000.0,
                 "end": 1764081030.0}]}

``component`` is ``<robot>_<node>`` (see :func:`component_name`). Kinds (``KINDS``) and what they do:

====================== ==============================================================================
``memory_leak``        allocates and keeps ``LEAK_BYTES_PER_S`` (touched, so RSS grows)
``wasted_cpu``         a thread busy-loops ``WASTED_CPU_SHARE`` of every 100 ms
``added_latency``      every callback sleeps ``ADDED_LATENCY_S`` first
``algorithmic_slowdown`` every callback sorts a history that grows by one entry per call (n log n)
``thread_leak``        starts a thread that never ends every ``LEAK_PERIOD_S``
``fd_leak``            opens ``os.devnull`` and keeps it every ``LEAK_PERIOD_S``
``delayed_communication`` every ``publish`` is handed to a queue and sent ``DELAY_S`` later
====================== ==============================================================================
At the end of its slice a bug stops and gives back what it took (memory, threads, fds), so a run has
faulty and healthy stretches, as the ground truth says.
"""
from __future__ import annotations

import heapq
import json
import logging
import mmap
import os
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

ENV_VAR = "FAULTMAS_PERFBUGS"
KINDS: tuple[str, ...] = ("memory_leak", "wasted_cpu", "added_latency", "algorithmic_slowdown",
                          "thread_leak", "fd_leak", "delayed_communication")
LEAK_BYTES_PER_S = 2 * 1024 * 1024
WASTED_CPU_SHARE = 0.3
ADDED_LATENCY_S = 0.004
LEAK_PERIOD_S = 0.2
DELAY_S = 0.05
POLL_S = 0.2
_LEAK_BLOCK = b"\x01" * (LEAK_BYTES_PER_S // 10)       # written into a new block every 0.1 s


class ScheduleError(ValueError):
    """A perf-bug schedule that cannot be used; names the file and what was expected."""


@dataclass(frozen=True)
class PerfBug:
    """One ground-truth fault instance: ``kind`` active in ``component`` from ``start`` to ``end`` (epoch s)."""

    component: str
    kind: str
    start: float
    end: float

    def to_dict(self) -> dict[str, Any]:
        return {"component": self.component, "kind": self.kind, "start": self.start, "end": self.end}


def component_name(robot: str, node: str) -> str:
    """The component's name in schedules, data sets and observations: ``faulty_kobuki_sim``."""
    return f"{robot}_{node}" if robot else node


AGENT_NODE = "agent"


def agent_component(agent: str) -> str:
    """An agent's component (its whole process): ``helper`` → ``helper_agent``, beside its robot's nodes."""
    return component_name(agent, AGENT_NODE)


def load_schedule(path: str | Path) -> list[PerfBug]:
    """The schedule's fault instances; raises ``ScheduleError`` naming the file and the bad entry."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise ScheduleError(f"{path}: cannot read the perf-bug schedule ({exc.strerror})") from None
    except json.JSONDecodeError as exc:
        raise ScheduleError(f"{path}:{exc.lineno}:{exc.colno}: not JSON ({exc.msg})") from None
    if not isinstance(data, dict) or not isinstance(data.get("faults"), list):
        raise ScheduleError(f"{path}: expected an object with a list 'faults'")
    bugs = []
    for i, entry in enumerate(data["faults"]):
        try:
            bug = PerfBug(str(entry["component"]), str(entry["kind"]), float(entry["start"]), float(entry["end"]))
        except (KeyError, TypeError, ValueError):
            raise ScheduleError(f"{path}: faults[{i}] needs component, kind, start and end (seconds)") from None
        if bug.kind not in KINDS:
            raise ScheduleError(f"{path}: faults[{i}]: unknown kind {bug.kind!r}; expected one of {', '.join(KINDS)}")
        if bug.end <= bug.start:
            raise ScheduleError(f"{path}: faults[{i}]: end must come after start")
        bugs.append(bug)
    return bugs


def write_schedule(path: str | Path, bugs: list[PerfBug]) -> None:
    Path(path).write_text(json.dumps({"faults": [b.to_dict() for b in bugs]}, indent=1), encoding="utf-8")


class BugRunner:
    """The bugs of one component: switches them on and off on time and does their harm while on."""

    def __init__(self, component: str, bugs: list[PerfBug] = (), path: Path | None = None,
                 clock: Callable[[], float] = time.time) -> None:
        self.component, self.path, self.clock = component, path, clock
        self.bugs = [b for b in bugs if b.component == component]
        self.active: set[str] = set()
        self._stop = threading.Event()
        self._leaked: list[mmap.mmap] = []
        self._fds: list[int] = []
        self._threads: list[threading.Thread] = []
        self._release_threads = threading.Event()
        self._history: list[float] = []
        self._delayed: list[tuple[float, int, Callable, Any]] = []
        self._delayed_lock = threading.Condition()
        self._sequence = 0

    # --- what the wrappers call -------------------------------------------------------------
    def before_callback(self) -> None:
        if "added_latency" in self.active:
            time.sleep(ADDED_LATENCY_S)
        if "algorithmic_slowdown" in self.active:
            self._history.append(self.clock() % 1.0)
            sorted(self._history)

    def publish(self, publish: Callable, msg: Any) -> None:
        if "delayed_communication" not in self.active:
            publish(msg)
            return
        with self._delayed_lock:
            self._sequence += 1
            heapq.heappush(self._delayed, (time.monotonic() + DELAY_S, self._sequence, publish, msg))
            self._delayed_lock.notify()

    # --- the threads ----------------------------------------------------------------------------
    def start(self) -> None:
        threading.Thread(target=self._switch, daemon=True, name="perfbugs-switch").start()
        threading.Thread(target=self._harm, daemon=True, name="perfbugs-harm").start()
        threading.Thread(target=self._send_delayed, daemon=True, name="perfbugs-delay").start()

    def stop(self) -> None:
        self._stop.set()
        self._release_threads.set()
        with self._delayed_lock:
            self._delayed_lock.notify()

    def _switch(self) -> None:
        """Every ``POLL_S``: re-read the schedule if it changed, then make ``active`` what it says now."""
        mtime = None
        while not self._stop.wait(POLL_S):
            if self.path is not None:
                try:
                    current = self.path.stat().st_mtime_ns
                    if current != mtime:
                        self.bugs = [b for b in load_schedule(self.path) if b.component == self.component]
                        mtime = current
                except (OSError, ScheduleError):
                    pass                         # being rewritten: the next poll reads it
            now = self.clock()
            wanted = {b.kind for b in self.bugs if b.start <= now < b.end}
            for kind in self.active - wanted:
                self.active.discard(kind)
                self._release(kind)
            self.active |= wanted

    def _release(self, kind: str) -> None:
        if kind == "memory_leak":
            for block in self._leaked:
                block.close()
            self._leaked.clear()
        elif kind == "fd_leak":
            for fd in self._fds:
                os.close(fd)
            self._fds.clear()
        elif kind == "thread_leak":
            self._release_threads.set()
            self._threads.clear()
            self._release_threads = threading.Event()
        elif kind == "algorithmic_slowdown":
            self._history = []

    def _harm(self) -> None:
        from robot_bridge.failure_log import FailureLog

        tick, last_leak = 0.1, 0.0
        failures = FailureLog(logging.getLogger(__name__), f"performance bugs of {self.component}: a leak")
        while not self._stop.is_set():
            started = time.monotonic()
            with failures.contained():   # a leak that hit a limit (EMFILE, no memory) must not end the others
                if "memory_leak" in self.active:         # anonymous maps: given back to the OS when closed
                    block = mmap.mmap(-1, len(_LEAK_BLOCK))
                    block.write(_LEAK_BLOCK)
                    self._leaked.append(block)
                if started - last_leak >= LEAK_PERIOD_S:
                    last_leak = started
                    if "fd_leak" in self.active:
                        self._fds.append(os.open(os.devnull, os.O_RDONLY))
                    if "thread_leak" in self.active:
                        thread = threading.Thread(target=self._release_threads.wait, daemon=True,
                                                  name="perfbugs-leaked")
                        thread.start()
                        self._threads.append(thread)
            if "wasted_cpu" in self.active:
                busy_until = started + tick * WASTED_CPU_SHARE
                while time.monotonic() < busy_until:
                    pass
            self._stop.wait(max(0.0, tick - (time.monotonic() - started)))

    def _send_delayed(self) -> None:
        from robot_bridge.failure_log import FailureLog

        failures = FailureLog(logging.getLogger(__name__), f"performance bugs of {self.component}: a delayed publish")
        while not self._stop.is_set():
            with self._delayed_lock:
                while not self._delayed and not self._stop.is_set():
                    self._delayed_lock.wait()
                if self._stop.is_set():
                    return
                due, _, publish, msg = self._delayed[0]
                wait = due - time.monotonic()
                if wait > 0:
                    self._delayed_lock.wait(wait)
                    continue
                heapq.heappop(self._delayed)
            with failures.contained():   # one message lost (logged), not every later one
                publish(msg)


def _wrap_callback(runner: BugRunner, callback: Callable) -> Callable:
    def wrapped(*args):
        runner.before_callback()
        return callback(*args)
    return wrapped


def install(node: Any, robot: str, bugs: list[PerfBug] = (), path: Path | None = None,
            component: str | None = None) -> BugRunner:
    """Wrap ``node``'s callbacks and publishers; the bugs of its component (from ``bugs``, and from the
    schedule file ``path``, re-read whenever it changes) switch on and off at their times.
    ``component``: the name in the schedule (default ``<robot>_<node name>``; an agent's bridge node
    is its agent's component, ``helper_agent``, since the bugs act on the whole process)."""
    runner = BugRunner(component or component_name(robot, node.get_name()), list(bugs), path)
    for entity in [*node.subscriptions, *node.timers]:
        entity.callback = _wrap_callback(runner, entity.callback)
    for publisher in node.publishers:
        original = publisher.publish
        publisher.publish = lambda msg, _publish=original: runner.publish(_publish, msg)
    runner.start()
    return runner


def install_from_env(node: Any, robot: str, component: str | None = None) -> BugRunner | None:
    """The hook :func:`robot_bridge.ros2.runtime.run_node` (every node) and ``Ros2Bridge.setup`` (an
    agent's process, as ``component`` ``<agent>_agent``) call: a no-op unless ``FAULTMAS_PERFBUGS`` is set.

    The schedule may be empty or even missing at start: an experiment writes the times once it knows
    when its recording began."""
    path = os.environ.get(ENV_VAR)
    if not path:
        return None
    node.get_logger().info(f"perf-bug hook installed; schedule {path}")
    return install(node, robot, path=Path(path), component=component)
