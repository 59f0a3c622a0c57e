"""Shipped plans and models usable by name, from any folder (issue 23): plans list|show|copy, diagnose NAME,
include("team_robot.asl")."""
from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

from agents.cli import main

REPO = Path(__file__).resolve().parents[2]


def test_list_shows_every_shipped_plan_with_what_it_is(capsys) -> None:
    assert main(["plans", "list"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"^team_robot\.asl +A robot of a team", out, re.M) and "turtlebot_hardware.yaml" in out


def test_copy_brings_a_plan_and_what_it_includes_and_never_overwrites(tmp_path: Path, capsys) -> None:
    assert main(["plans", "copy", "team_robot", str(tmp_path)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["faulty.asl", "geometry.asl", "helper.asl", "team_robot.asl"]
    assert main(["asl", "check", str(tmp_path / "team_robot.asl")]) == 0
    assert main(["plans", "copy", "team_robot", str(tmp_path)]) == 2
    assert "already exist" in capsys.readouterr().err
    assert main(["plans", "show", "nonesuch"]) == 2


def test_diagnose_takes_a_shipped_model_by_name(tmp_path: Path) -> None:
    obs = tmp_path / "obs.json"
    obs.write_text(json.dumps({"commanded_forward": 1, "encoders_report_motion": 0, "left_over_current": 1,
                               "right_over_current": 1}))
    done = subprocess.run([sys.executable, "-m", "agents", "diagnose", "turtlebot_hardware", "--obs", str(obs),
                           "--json"], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert ["left_wheel", "right_wheel"] in json.loads(done.stdout)["diagnoses"]


def test_a_program_anywhere_includes_a_shipped_plan_by_name(tmp_path: Path, capsys) -> None:
    mine = tmp_path / "mine.asl"
    mine.write_text('{ include("team_robot.asl") }\n+!extra <- .print("mine").\n')
    assert main(["asl", "check", str(mine)]) == 0, capsys.readouterr().err
    (tmp_path / "geometry.asl").write_text("norm(A, A).\n")        # a file beside mine wins over the shipped one
    from agentspeak.sources import find_source
    assert find_source("geometry.asl", str(tmp_path)) == str(tmp_path / "geometry.asl")
