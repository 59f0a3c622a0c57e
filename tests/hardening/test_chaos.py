"""Issue 22, found item 3 (chaos): a robot the run waits for, killed with SIGKILL mid-run, is named in
the run's outcome with its own exit status, within seconds rather than at the run's timeout, and the
exit code of ``faultmas run`` tells it from a wrong diagnosis."""
from __future__ import annotations

import signal
import threading
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


def test_a_helper_frozen_for_seconds_is_taken_back_after_it_thaws():
    frozen: list[str] = []

    def freeze_the_helper(mark, kill):
        if mark.agent == "faulty" and mark.step == "helper_found" and not frozen:
            frozen.append(mark.detail)
            kill(mark.detail, signal.SIGSTOP)   # its link lease (1 s) expires: faulty sees it gone
            threading.Timer(5.0, kill, (mark.detail, signal.SIGCONT)).start()
    result = run_scenario(paper_scenario("encoders", seed=5), processes=True, timeout=240,
                          on_mark=freeze_the_helper)
    assert frozen, "no helper was found"
    assert result.died == [] and result.finished, [(m.agent, m.step, m.detail) for m in result.marks]
    assert result.robots[0].diagnosis == "encoders"
    helpers = [m.detail for m in result.marks if m.agent == "faulty" and m.step == "helper_found"]
    assert helpers.count(frozen[0]) >= 2, helpers  # the thawed helper was taken back


def test_an_agent_that_dies_before_it_is_reachable_does_not_hold_the_others(tmp_path):
    """``mas run --processes`` starts each agent with ``--wait-for-peers 60``: a peer whose process died
    on start (here: bad initial beliefs) once held the others for the whole minute."""
    from tests.agents.distributed_fixtures import mas_run, write_files
    write_files(tmp_path, {"a.asl": '!start.\n+!start <- .print("started"); .stopMAS.\n', "b.asl": "",
                           "m.mas2j": 'MAS m { agents: a; b [beliefs="((("]; }\n'})
    started = time.monotonic()
    run = mas_run(tmp_path / "m.mas2j", "--processes", "--timeout", "120")
    assert run.finish(timeout=150) == 1  # an agent process failed
    assert "[a] started" in run.out
    assert time.monotonic() - started < 50  # not after the 60 s wait for b (generous for a loaded machine)
    assert any("died before they became reachable" in line and "b" in line for line in run.err)


def test_a_stopped_process_is_named_as_frozen_and_no_longer_once_it_continues():
    """What a run says about a freeze (``RunResult.frozen``): the process stopped by SIGSTOP, and for how long
    (``FreezeWatch``), even once it was continued."""
    import subprocess
    import sys

    import psutil

    from robot_bridge.processes import FreezeWatch, frozen

    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    watch = FreezeWatch(lambda: {"sleeper": sleeper}, interval=0.1).__enter__()
    try:
        assert frozen({"sleeper": sleeper}) == []
        sleeper.send_signal(signal.SIGSTOP)
        deadline = time.monotonic() + 10
        while psutil.Process(sleeper.pid).status() != psutil.STATUS_STOPPED and time.monotonic() < deadline:
            time.sleep(0.05)
        assert frozen({"sleeper": sleeper, "gone": subprocess.Popen([sys.executable, "-c", ""])}) == ["sleeper"]
        time.sleep(0.5)  # the watch samples every 0.1 s
        sleeper.send_signal(signal.SIGCONT)
        deadline = time.monotonic() + 10
        while psutil.Process(sleeper.pid).status() == psutil.STATUS_STOPPED and time.monotonic() < deadline:
            time.sleep(0.05)
        assert frozen({"sleeper": sleeper}) == []
        watch.__exit__()
        [(name, seconds)] = watch.report()
        assert name == "sleeper" and seconds > 0
    finally:
        watch.__exit__()
        sleeper.kill()
        sleeper.wait()
