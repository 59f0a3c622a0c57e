"""plans/team_robot.asl's own rules, run by the interpreter without a robot: who may help."""
from __future__ import annotations

import agents.progress  # noqa: F401  (registers .progress)
from agentspeak.parser import parse_program, parse_term
from agentspeak.runtime import LocalRuntime
from agentspeak.solver import solve_first
from agents.cooperative import plans_dir


def decided(components: str) -> bool:
    """A team robot that suspected itself decides ``components``: is it available to help afterwards?"""
    path = plans_dir().joinpath("team_robot.asl")
    runtime = LocalRuntime(printer=lambda name, text: None)
    agent = runtime.add_agent("robot1", program=parse_program(path.read_text(), str(path)), source_file=str(path),
                              extra_beliefs=[parse_term("self_suspect"), parse_term("diagnosing")],
                              extra_goals=[parse_term(f"decide({components})")])
    runtime.run(timeout=5, stop_when_idle=False)
    return solve_first(agent, parse_term("available"), {})


def test_a_robot_found_healthy_after_a_false_alarm_helps_the_others_again():
    assert decided("[]")


def test_a_robot_with_a_diagnosed_fault_never_helps():
    assert not decided("[left_encoder,right_encoder]")
