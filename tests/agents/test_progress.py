"""``.progress``: reports go to the architecture's hook; a malformed control message is not a report."""
from __future__ import annotations

from agents.progress import ProgressReport
from agents.robot_arch import RobotArch
from agentspeak.runtime import LocalRuntime
from robot_bridge.logging_bridge import LoggingBridge


def test_progress_reports_reach_the_runner_in_order_with_details():
    reports = []
    runtime = LocalRuntime(printer=lambda n, t: None)
    bridge = LoggingBridge("r1")
    bridge.setup()
    runtime.add_agent("r1", source="!go. +!go <- .progress(started, 1.5); .progress(diagnosed, [a, b]); "
                                    ".progress(done).",
                      arch=RobotArch(runtime, bridge, on_progress=reports.append))
    runtime.run(timeout=5)
    assert reports == [ProgressReport("r1", "started", "1.5"), ProgressReport("r1", "diagnosed", "[a,b]"),
                       ProgressReport("r1", "done", "")]


def test_a_step_that_is_not_an_atom_fails_the_plan_with_a_reason():
    lines = []
    runtime = LocalRuntime(printer=lambda n, t: lines.append(t))
    runtime.add_agent("r2", source='!go. +!go <- .progress("x"). -!go[error(E)] <- .print(E).')
    runtime.run(timeout=5)
    assert lines and lines[0] != ""


def test_control_messages_become_reports_only_when_well_formed():
    assert ProgressReport.from_message({"command": "progress", "agent": "a", "step": "s", "detail": "d"}) \
        == ProgressReport("a", "s", "d")
    for bad in ({"command": "stop"}, {"command": "progress", "agent": 3, "step": "s"},
                {"command": "progress", "agent": "a", "step": ""}):
        assert ProgressReport.from_message(bad) is None
