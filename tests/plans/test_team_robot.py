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


def test_a_new_task_ends_what_the_last_one_left_going():
    # issue 22's soak: a task past its budget left a robot helping (searching for a robot that had a new task
    # by then) or diagnosing (asking round after round for a helper) into the next task, busy for it
    path = plans_dir().joinpath("team_robot_tasks.asl")
    runtime = LocalRuntime(printer=lambda name, text: None)
    robot = runtime.add_agent("robot1", program=parse_program(path.read_text(), str(path)), source_file=str(path),
                              extra_beliefs=[parse_term("helping(robot2)"), parse_term("help_at(robot2, unknown)"),
                                             parse_term("diagnosing"), parse_term("self_suspect")],
                              extra_goals=[parse_term("awaitHelper([[left_motor]], 1)")])
    runtime.add_agent("fleet", source="!go.\n+!go <- .wait(300); .send(robot1, tell, task(7, 1.0, 2.0, 90.0)).\n")
    runtime.run(timeout=2, stop_when_idle=False)
    goals = {str(im.event_literal).split("(")[0] for i in robot.intentions() for im in i.stack}
    assert "awaitHelper" not in goals and "askForHelp" not in goals, goals
    assert solve_first(robot, parse_term("available"), {})
    assert solve_first(robot, parse_term("start_pose(1.0, 2.0, 90.0)"), {})


def test_a_robot_whose_camera_has_failed_does_not_offer_help():
    """``camera_failed(Part)`` (robot_bridge/percepts.py): it cannot look for anyone, so it is not available, says
    why when asked, and a search it is in ends at once."""
    path = plans_dir().joinpath("team_robot.asl")
    printed = []
    runtime = LocalRuntime(printer=lambda name, text: printed.append(text))
    robot = runtime.add_agent("robot1", program=parse_program(path.read_text(), str(path)), source_file=str(path),
                              extra_beliefs=[parse_term("camera_failed(detector)"), parse_term("odom(0, 0, 0)")],
                              extra_goals=[parse_term("search(robot2, 0)")])
    runtime.add_agent("robot2", source="!go.\n+!go <- .send(robot1, achieve, helpMe(robot2, at(1, 2))).\n")
    runtime.run(timeout=2, stop_when_idle=True)
    assert not solve_first(robot, parse_term("available"), {})
    assert "robot2 needs help, but my camera's detector has failed" in printed, printed
    assert "my camera's detector has failed: I cannot see robot2" in printed, printed
