"""``faultmas sim``: scripted runs through the real CLI dispatcher."""
import csv

import pytest

from agents.cli import main
from robot_bridge.cli import parse_script


def test_parse_script():
    actions = parse_script(" move(0.5); turn(-90, 30) ;stop; set_fault(left_actuator, 0.5)")
    assert [(a.name, a.args) for a in actions] == [
        ("move", (0.5,)), ("turn", (-90, 30)), ("stop", ()), ("set_fault", ("left_actuator", 0.5))]
    with pytest.raises(ValueError, match="column 11: expected ';'"):
        parse_script("move(0.5) turn(9)")
    with pytest.raises(ValueError, match="'Foo' is neither a number nor an atom"):
        parse_script("move(Foo)")


def test_sim_run_prints_completions_and_writes_the_trajectory(tmp_path, capsys):
    out = tmp_path / "run.csv"
    code = main(["sim", "run", "--fault", "encoders", "--script", "move(0.3); turn(45)", "--csv", str(out)])
    text = capsys.readouterr().out
    assert code == 1                                    # the fault makes the actions fail
    assert "move(0.3)                FAILED no_progress" in text
    rows = list(csv.DictReader(out.open()))
    faulty = [r for r in rows if r["robot"] == "faulty"]
    assert float(faulty[-1]["x"]) > 0.1 and float(faulty[-1]["odom_x"]) == 0.0
    assert {r["robot"] for r in rows} == {"faulty", "helper"}


def test_sim_run_plots(tmp_path, capsys):
    image = tmp_path / "run.png"
    assert main(["sim", "run", "--robots", "solo", "--script", "turn(30)", "--plot", str(image)]) == 0
    assert image.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bad_arguments_exit_2_with_a_message(capsys):
    assert main(["sim", "run", "--fault", "wobbly"]) == 2
    assert "unknown fault 'wobbly'" in capsys.readouterr().err
    assert main(["sim", "run", "--robots", "a,a"]) == 2


def test_sim_bridges_lists_the_entry_points(capsys):
    assert main(["sim", "bridges"]) == 0
    assert "ros2, sim" in capsys.readouterr().out
