"""``faultmas run --secure`` (issue 22): the run's project gives every robot a key pair made for the run, so
its agent processes sign what they send and refuse what no member signed (the secure profile of ``mas run``)."""
import stat

from agents.cooperative import paper_scenario, team_scenario, write_project
from agentspeak.mas2j import load_mas2j


def test_a_secure_run_lists_a_key_per_robot_and_keeps_private_keys_private(tmp_path):
    from agents.transport.identity import project_identity

    scenario = team_scenario(3, 1, seed=2)
    project = load_mas2j(str(write_project(scenario, tmp_path, secure=True)))
    identity = project_identity(project, ["robot1"])
    assert identity is not None                                   # the secure profile is on
    for robot in ("robot1", "robot2", "robot3", "environment"):
        assert (tmp_path / "keys" / f"{robot}.pub").is_file()
        assert stat.S_IMODE((tmp_path / "keys" / f"{robot}.key").stat().st_mode) == 0o600
    # the run's own process serves the robots: it signs their percepts, results and clock as the environment,
    # which is no member (it can neither send speech acts nor stop the MAS)
    from agents.transport.identity import ENVIRONMENT
    hub = project_identity(project, [ENVIRONMENT])
    assert hub.can_sign(ENVIRONMENT) and ENVIRONMENT not in hub.members
    assert hub.members == {"robot1", "robot2", "robot3"}
    (tmp_path / "plain").mkdir()
    default = load_mas2j(str(write_project(paper_scenario(), tmp_path / "plain")))
    assert project_identity(default) is None                      # without --secure: the default profile


def test_secure_needs_agent_processes_on_the_embedded_simulator(capsys):
    from agents.cli import main

    assert main(["run", "--secure", "--in-process"]) == 2
    assert "--secure" in capsys.readouterr().err
