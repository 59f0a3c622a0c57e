"""``faultmas run --bridge NAME`` for any installed bridge but ``sim`` and ``ros2``: the same plans and agent
processes, the robots whatever the bridge reaches (``faultmas sim serve`` through ``zenoh``, a real robot).

faultmas neither places nor breaks these robots: they stand where they stand (the plans are told the
paper's set-up, Faulty side-on 1.5 m beside Helper) and ``--fault`` names the fault the robot has (injected
on the robot's side, e.g. ``faultmas sim serve --fault faulty=encoders``), against which the diagnosis is
scored. Time is the wall clock, as on real robots. The paper's two robots only: a team's start poses are
drawn by the simulator that runs it.
"""
from __future__ import annotations

from typing import Callable, TextIO

from agents.cooperative import Mark, RunResult, Scenario, run_agent_processes
from agents.ros2_run import log_clock


def run_on_bridge(scenario: Scenario, choice, timeout: float = 120.0, out: TextIO | None = None,
                  echo: Callable[[Mark], None] | None = None) -> RunResult:
    """Run ``scenario``'s agents as processes whose robots are reached through ``choice``
    (an ``agents.environment.BridgeChoice``)."""
    names = [r.name for r in scenario.robots]
    if names != ["faulty", "helper"]:
        raise ValueError(f"--bridge {choice.name} runs the paper's two robots (faulty and helper) only")
    log = run_agent_processes(scenario, choice.agent_args(), timeout, clock=log_clock(), out=out, echo=echo)
    return RunResult(scenario, log.results(), log.marks, log.done.is_set(), None, list(log.died))
