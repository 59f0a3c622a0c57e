"""Issue 22, found item 3 (chaos): a robot the run waits for, killed with SIGKILL mid-run, is named in
the run's outcome with its own exit status, within seconds rather than at the run's timeout, and the
exit code of ``faultmas run`` tells it from a wrong diagnosis."""
from __future__ import annotations

import signal
import time

from agents.cooperative import paper_scenario, run_scenario
from agents.demo_cli import RUN_EXIT_CODES, _summary


def test_a_killed_faulty_robot_ends_the_run_promptly_and_is_named():
    killed: list[float] = []

    def kill_faulty_once_it_detects(mark, kill):
        if mark.agent == "faulty" and mark.step == "fault_detected" and not killed:
            killed.append(time.monotonic())
            kill("faulty")
    started = time.monotonic()
    result = run_scenario(paper_scenario("encoders", seed=5), processes=True, timeout=240,
                          on_mark=kill_faulty_once_it_detects)
    assert killed, "the faulty robot never detected its fault"
    assert result.died == [("faulty", -signal.SIGKILL)]
    assert result.outcome == "died" and RUN_EXIT_CODES[result.outcome] not in (RUN_EXIT_CODES["wrong"], 0)
    assert "the run ended early: agent faulty: killed by SIGKILL (exit -9)" in _summary(result)
    # ended by the death (a grace of seconds), not by the 240 s timeout; generous for a loaded machine
    assert time.monotonic() - killed[0] < 120, time.monotonic() - started
