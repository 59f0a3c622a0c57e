"""The perf-bug hook: schedule files checked, bugs on and off at their times, what they took given back."""
from __future__ import annotations

import json
import threading
import time

import psutil
import pytest

from robot_bridge.ros2 import perfbugs
from robot_bridge.ros2.perfbugs import BugRunner, PerfBug, ScheduleError, load_schedule, write_schedule


def test_schedules_are_checked_with_the_file_named(tmp_path):
    path = tmp_path / "s.json"
    path.write_text('{"faults": [{"component": "a_b", "kind": "gremlins", "start": 1, "end": 2}]}')
    with pytest.raises(ScheduleError, match=r"s\.json: faults\[0\]: unknown kind 'gremlins'; expected one of memory_leak"):
        load_schedule(path)
    path.write_text('{"faults": [{"component": "a_b", "kind": "fd_leak", "start": 2, "end": 1}]}')
    with pytest.raises(ScheduleError, match="end must come after start"):
        load_schedule(path)
    path.write_text('{"faults": [{"kind": "fd_leak"}]}')
    with pytest.raises(ScheduleError, match=r"faults\[0\] needs component, kind, start and end"):
        load_schedule(path)
    path.write_text("{oops")
    with pytest.raises(ScheduleError, match=r"s\.json:1:2: not JSON"):
        load_schedule(path)
    bugs = [PerfBug("faulty_kobuki_sim", "memory_leak", 1.0, 2.0)]
    write_schedule(path, bugs)
    assert load_schedule(path) == bugs


def _wait(predicate, timeout=10.0):
    deadline = time.monotonic() + timeout
    while not predicate() and time.monotonic() < deadline:
        time.sleep(0.05)
    return predicate()


def test_leaks_grow_while_on_and_are_given_back_at_the_end(tmp_path):
    me = psutil.Process()
    path = tmp_path / "schedule.json"
    write_schedule(path, [])
    runner = BugRunner("faulty_motion_decomposer", path=path)
    runner.start()
    try:
        fds, threads, rss = me.num_fds(), threading.active_count(), me.memory_info().rss
        now = time.time()
        write_schedule(path, [PerfBug("faulty_motion_decomposer", kind, now, now + 2.0)
                              for kind in ("fd_leak", "thread_leak", "memory_leak")]
                       + [PerfBug("helper_kobuki_sim", "wasted_cpu", now, now + 2.0)])    # someone else's
        assert _wait(lambda: me.num_fds() >= fds + 2 and threading.active_count() >= threads + 2
                     and me.memory_info().rss >= rss + 2 * 2**20)
        assert runner.active == {"fd_leak", "thread_leak", "memory_leak"}
        assert _wait(lambda: not runner.active)
        assert _wait(lambda: me.num_fds() <= fds and threading.active_count() <= threads + 0
                     and me.memory_info().rss < rss + 2 * 2**20)
    finally:
        runner.stop()


def test_callbacks_and_publishing_are_slowed_only_while_on():
    runner = BugRunner("c")
    runner.start()
    sent = []
    try:
        runner.publish(sent.append, 1)
        assert sent == [1]                          # no bug: published at once
        runner.active.add("delayed_communication")
        started = time.monotonic()
        runner.publish(sent.append, 2)
        assert sent == [1]
        assert _wait(lambda: sent == [1, 2])
        assert time.monotonic() - started >= perfbugs.DELAY_S
        runner.active.add("added_latency")
        started = time.perf_counter()
        runner.before_callback()
        assert time.perf_counter() - started >= perfbugs.ADDED_LATENCY_S
    finally:
        runner.stop()


def test_a_delayed_publish_that_raises_loses_that_message_not_the_later_ones():
    """Before: one publish that raised (a node being destroyed) ended the delaying thread, and every later
    message of ``delayed_communication`` stayed queued for ever."""
    now = time.time()
    runner = BugRunner("a_node", [PerfBug("a_node", "delayed_communication", now - 1.0, now + 60.0)])
    runner.start()
    sent = []

    def publish(msg):
        if msg == "bad":
            raise RuntimeError("publisher destroyed")
        sent.append(msg)

    try:
        assert _wait(lambda: runner.active == {"delayed_communication"})
        for msg in ("bad", "after"):
            runner.publish(publish, msg)
        assert _wait(lambda: sent == ["after"])
    finally:
        runner.stop()
