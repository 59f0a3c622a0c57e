"""``faultmas sim serve``: a simulated world served over a real Zenoh session on loopback to an agent that was
started by hand in another process with ``--bridge zenoh`` (issue 23)."""
from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import textwrap

import pytest

pytest.importorskip("zenoh")

from agents.transport import loopback_endpoint  # noqa: E402

PLAN = textwrap.dedent("""\
    !go.
    +!go <- move(0.5); .wait(100); ?odom(X, _, _); .print("believes x=", math.round(X * 10) / 10); .stopMAS.
""")


@pytest.mark.timeout(120)
@pytest.mark.parametrize("secure", [False, True], ids=["default", "secure"])
def test_an_agent_in_another_process_drives_a_served_robot(tmp_path, secure: bool) -> None:
    """``secure``: the project lists the agents' keys and the environment's (its environment line): the server
    signs as the environment (``--project``), the agent signs its actions and checks the rest."""
    (tmp_path / "drive.asl").write_text(PLAN)
    endpoint = loopback_endpoint()
    project: list[str] = []
    if secure:
        from agents.transport.identity import generate_keys
        generate_keys(tmp_path / "keys", ["rover", "other", "environment"])
        (tmp_path / "lab.mas2j").write_text(
            'MAS lab {\n  environment: sim("key=keys/environment.pub")\n'
            '  agents: rover drive.asl [key="keys"]; other drive.asl [key="keys"];\n}\n')
        project = ["--project", str(tmp_path / "lab.mas2j")]
    server = subprocess.Popen([sys.executable, "-m", "agents", "sim", "serve", "--mas", "lab", "--robots",
                               "rover,other", "--fault", "other=encoders", "--listen", endpoint, "--timeout", "100",
                               *project], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        banner = server.stdout.readline()
        assert f"robots rover (fault none), other (fault encoders) of MAS lab on {endpoint}" in banner, \
            banner + server.stderr.read() if not banner else banner
        agent = subprocess.run([sys.executable, "-m", "agents", "agent", "run", str(tmp_path / "drive.asl"),
                                "--name", "rover", "--mas", "lab", "--connect", endpoint, "--bridge", "zenoh",
                                "--timeout", "60", *project], capture_output=True, text=True, timeout=90)
        assert agent.returncode == 0, agent.stderr
        assert "[rover] believes x=0.5" in agent.stdout
        assert "dropped" not in agent.stderr, agent.stderr      # every percept, result and tick was signed
    finally:
        server.send_signal(signal.SIGINT)
        out, err = server.communicate(timeout=30)
    assert server.returncode == 0, err
    truth = re.search(r"^rover: truth \(([-\d.]+), ([-\d.]+),", out, re.M)
    assert truth and abs(float(truth.group(1)) - 0.5) < 0.02, out   # the robot really drove, in the served world
    assert "other: truth (0.000, -1.500" in out  # the second robot stood beside it, untouched
    assert "1 action requests served" in out


def test_bad_input_is_one_line_and_exit_2() -> None:
    done = subprocess.run([sys.executable, "-m", "agents", "sim", "serve", "--mas", "lab", "--fault", "nobody=encoders"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr.strip() == ("faultmas sim serve: --fault expects ROBOT=KIND with ROBOT among faulty, helper, "
                                   "got 'nobody=encoders'")


@pytest.mark.timeout(200)
def test_faultmas_run_diagnoses_a_served_pair_through_the_zenoh_bridge() -> None:
    """``faultmas run --bridge zenoh``: any installed bridge, here the robots of a ``faultmas sim serve``."""
    endpoint = loopback_endpoint()
    server = subprocess.Popen([sys.executable, "-m", "agents", "sim", "serve", "--mas", "coop", "--fault",
                               "faulty=encoders", "--listen", endpoint, "--timeout", "180"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert "of MAS coop" in server.stdout.readline()
        run = subprocess.run([sys.executable, "-m", "agents", "run", "--bridge", "zenoh", "--bridge-option",
                              f"connect={endpoint}", "--fault", "encoders", "--quiet", "--json", "--timeout", "150"],
                             capture_output=True, text=True, timeout=180)
    finally:
        server.send_signal(signal.SIGINT)
        server.communicate(timeout=30)
    assert run.returncode == 0, run.stderr
    result = json.loads(run.stdout)
    assert [(r["robot"], r["fault"], r["diagnosis"]) for r in result["robots"]] == [("faulty", "encoders", "encoders")]


@pytest.mark.parametrize("argv, message", [
    (["--bridge", "nosuch"], "faultmas run: unknown robot bridge 'nosuch'; known bridges: "),
    (["--bridge", "zenoh", "--bridge-option", "conect=tcp/127.0.0.1:1"],
     "faultmas run: robot bridge 'zenoh' has no option 'conect'; its options: action_timeout, connect, mas, session"),
    (["--bridge", "sim", "--bridge-option", "seed=1"], "faultmas run: --bridge sim takes no --bridge-option here"),
])
def test_faultmas_run_refuses_unknown_bridges_and_options(argv, message, capsys) -> None:
    from agents.cli import main
    assert main(["run", *argv]) == 2
    assert message in capsys.readouterr().err
