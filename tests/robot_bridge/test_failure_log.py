"""FailureLog: a failure that repeats is said once, counted always, and named when it persists."""
import logging

import pytest

from robot_bridge.failure_log import FailureLog

log = logging.getLogger("test_failure_log")


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def fail(failures: FailureLog, times: int, detail: str = "") -> None:
    for _ in range(times):
        with failures.contained(detail):
            raise ValueError("bad frame")


def test_a_repeating_failure_is_logged_once_with_its_traceback_then_at_10_100_1000(caplog):
    failures = FailureLog(log, "robot a's camera detector", persistent_after=10)
    with caplog.at_level(logging.WARNING, logger=log.name):
        fail(failures, 1500, "frame at 1.00 s")
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 4, lines
    assert lines[0].startswith("robot a's camera detector failed (frame at 1.00 s): ValueError('bad frame')")
    assert caplog.records[0].exc_info is not None                  # the traceback, once
    assert "10 times in a row" in lines[1] and "(persistent now)" in lines[1]
    assert "100 times in a row" in lines[2] and "1000 times in a row" in lines[3]
    assert failures.total == failures.consecutive == 1500 and failures.persistent


def test_a_success_ends_the_episode_and_a_persistent_one_says_it_recovered(caplog):
    failures = FailureLog(log, "tap", persistent_after=3)
    with caplog.at_level(logging.WARNING, logger=log.name):
        fail(failures, 2)
        with failures.contained():
            pass
        assert failures.consecutive == 0 and not failures.persistent and len(caplog.records) == 1
        fail(failures, 3)
        assert failures.persistent
        with failures.contained():
            pass
    assert not failures.persistent and failures.total == 5
    assert caplog.records[-1].getMessage() == "tap works again after 3 failures in a row (5 in all)"


def test_new_episodes_within_the_quiet_time_are_counted_and_told_in_the_next_line(caplog):
    clock = Clock()
    failures = FailureLog(log, "tick", quiet=60.0, clock=clock)
    with caplog.at_level(logging.WARNING, logger=log.name):
        for _ in range(5):               # fails every other call
            fail(failures, 1)
            failures.succeeded()
            clock.now += 1.0
        assert len(caplog.records) == 1
        clock.now += 60.0
        fail(failures, 1)
    assert failures.total == 6
    assert "4 earlier failures not logged one by one" in caplog.records[-1].getMessage()


def test_base_exceptions_go_through():
    failures = FailureLog(log, "loop")
    with pytest.raises(KeyboardInterrupt):
        with failures.contained():
            raise KeyboardInterrupt
    assert failures.total == 0
