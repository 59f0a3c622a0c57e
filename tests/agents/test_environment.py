"""``environment: sim`` (any bridge) in a ``.mas2j`` gives its agents robots; ``faultmas mas run --bridge`` and
``--bridge-option`` choose one from the command line; unknown bridges and options are errors (issue 23)."""
from __future__ import annotations

import logging
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from agents.cli import main

# each robot drives half a metre and says where its own odometry believes it is; once both have, faulty stops the MAS
DRIVER = textwrap.dedent("""\
    !go.
    +!go <- move(0.5); .wait(100); ?odom(X, _, _); .my_name(Me); .print(Me, " at x=", math.round(X * 10) / 10);
            .send(faulty, tell, done(Me)).
    +done(_) : .count(done(_), 2) <- .stopMAS.
""")


def project(tmp_path: Path, environment: str, agents: str = "faulty driver.asl; helper driver.asl;") -> str:
    (tmp_path / "driver.asl").write_text(DRIVER)
    file = tmp_path / "robots.mas2j"
    file.write_text(f"MAS robots {{\n  {environment}\n  agents: {agents}\n}}\n")
    return str(file)


def test_environment_sim_gives_every_agent_its_robot_in_one_world(tmp_path, capsys) -> None:
    code = main(["mas", "run", project(tmp_path, 'environment: sim("seed=3")'), "--timeout", "60"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "[faulty] faulty at x=0.5" in out and "[helper] helper at x=0.5" in out


def test_without_an_environment_move_is_no_robot_action(tmp_path, capsys) -> None:
    """The same project without ``environment:``: ``move`` reaches no robot (the test above can fail)."""
    main(["mas", "run", project(tmp_path, ""), "--timeout", "20"])
    assert "at x=" not in capsys.readouterr().out


def test_bridge_on_the_command_line_wins_and_its_options_are_checked(tmp_path, capsys) -> None:
    file = project(tmp_path, "environment: env.JavaEnv")
    assert main(["mas", "run", file, "--bridge", "sim", "--timeout", "60"]) == 0
    assert "[faulty] faulty at x=0.5" in capsys.readouterr().out
    assert main(["mas", "run", file, "--bridge", "sim", "--bridge-option", "fualt=encoders"]) == 2
    err = capsys.readouterr().err
    assert "robot bridge 'sim' has no option 'fualt'; its options: " in err and "fault" in err
    assert main(["mas", "run", file, "--bridge", "simm"]) == 2
    assert "unknown robot bridge 'simm'; known bridges: " in capsys.readouterr().err


def test_a_bad_environment_names_the_project_file_and_line(tmp_path, capsys) -> None:
    assert main(["mas", "run", project(tmp_path, "\n  environment: simm")]) == 2
    assert f"{tmp_path / 'robots.mas2j'}:3: environment simm: unknown robot bridge 'simm'" in capsys.readouterr().err
    assert main(["mas", "run", project(tmp_path, 'environment: sim("speed=-1")')]) == 1   # checked as it starts
    assert "bridge 'sim', options {'speed': -1}: speed must be >= 0" in capsys.readouterr().err
    assert main(["mas", "run", project(tmp_path, 'environment: sim("camra=true")')]) == 2
    assert "robots.mas2j:2: environment sim: robot bridge 'sim' has no option 'camra'" in capsys.readouterr().err


def test_a_java_environment_class_is_named_in_a_warning(tmp_path, capsys, caplog) -> None:
    with caplog.at_level(logging.WARNING, logger="faultmas.agents"):
        main(["mas", "run", project(tmp_path, "environment: env.JavaEnv"), "--timeout", "20"])
    assert "environment env.JavaEnv is a Java class, which faultmas cannot run" in caplog.text


@pytest.mark.timeout(180)
def test_environment_sim_with_one_process_per_agent_shares_the_served_world(tmp_path) -> None:
    """``--processes``: the world stays in the launcher, served over a real Zenoh session on loopback; each
    agent process drives its robot through the zenoh bridge."""
    done = subprocess.run([sys.executable, "-m", "agents", "mas", "run", project(tmp_path, "environment: sim"),
                           "--processes", "--timeout", "120"], capture_output=True, text=True, timeout=170,
                          cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "[faulty] faulty at x=0.5" in done.stdout and "[helper] helper at x=0.5" in done.stdout, done.stderr
