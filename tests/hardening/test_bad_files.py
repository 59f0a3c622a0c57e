"""Issue 22, found items 1, 5 and 6 on the file boundary: every bad file gets one located error
(``file:line[:column]: reason``) and exit status 2 from the command a user would run, never a traceback."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from agents.cli import main

REPO = Path(__file__).resolve().parents[2]
MODEL = str(REPO / "plans" / "turtlebot_hardware.yaml")


def run(capsys, *argv: str) -> str:
    assert main(list(argv)) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err


@pytest.mark.parametrize("content, expected", [
    (b'+!g <- .print("caf\xe9").\n', "x.asl:1:19: this file is not UTF-8 text"),
    (b"n(" + b"7" * 5000 + b").\n", "x.asl:1: integer literal of 5000 digits is too long"),
    (b"p(" + b"f(" * 20000 + b"a" + b")" * 20000 + b").\n", "x.asl:1:402: nested too deeply"),
    (b"p(" + b"[" * 40000 + b"]" * 40000 + b").\n", "x.asl:1:202: nested too deeply"),
    (b"+!g <- X = " + b" + ".join([b"1"] * 20000) + b".\n", "x.asl:1: nested too deeply"),
    (b'{ include("a\x00b.asl") }\n', "x.asl:1: cannot include 'a"),
])
def test_asl_check_locates_each_bad_file(tmp_path, capsys, content, expected):
    (tmp_path / "x.asl").write_bytes(content)
    err = run(capsys, "asl", "check", str(tmp_path / "x.asl"))
    assert expected in err.replace(str(tmp_path) + "/", "")


@pytest.mark.timeout(120)  # before: every error re-parsed the rest, minutes for this file (found by the fuzz)
def test_asl_check_stops_after_a_hundred_errors(tmp_path, capsys):
    (tmp_path / "x.asl").write_bytes(b"b(1).\n" + b"@c(X).\n" * 30000)
    err = run(capsys, "asl", "check", str(tmp_path / "x.asl"))
    assert "x.asl:101: too many errors (100); the rest of the file is not checked" in err.replace(str(tmp_path) + "/", "")
    assert err.count("x.asl:") == 101


@pytest.mark.parametrize("agents, expected", [
    (b"a #99999999999999999999;", "p.mas2j:3:8: instance count 99999999999999999999 is out of range"),
    (b"a #2;\n    a1;", "p.mas2j:4:5: agent name 'a1' is declared twice"),
    (b"a; a;", "p.mas2j:3:8: agent name 'a' is declared twice"),
    (b'a "x\x00y.asl";', "p.mas2j:3:7: a NUL character in the agent's source file name"),
])
def test_project_files_locate_each_bad_declaration(tmp_path, capsys, agents, expected):
    (tmp_path / "p.mas2j").write_bytes(b"MAS t {\n  agents:\n    " + agents + b"\n}\n")
    (tmp_path / "a.asl").write_text("!g.\n+!g.\n")
    err = run(capsys, "mas", "run", str(tmp_path / "p.mas2j"), "--timeout", "5")
    assert expected in err.replace(str(tmp_path) + "/", "")


@pytest.mark.parametrize("name, content, expected", [
    ("m.yaml", b"system: s\xe9\n", "m.yaml:1:10: this YAML file is not UTF-8 text"),
    ("m.bench", b"INPUT(a\xe9)\n", "m.bench:1:8: this netlist is not UTF-8 text"),
    ("m.yaml", b"system: s\ncomponents: " + b"[" * 20000 + b"]" * 20000 + b"\n", "m.yaml: nested too deeply"),
    ("m.yaml", b'system: s\ncomponents: [a]\nobservations: [o]\nbehaviour:\n  - "' + b"!" * 20000 + b'o"\n',
     "m.yaml:5:5: bad formula: nested too deeply"),
    ("m.yaml", b'system: s\ncomponents: [a]\nobservations: [o]\nbehaviour:\n  - "' + b"(" * 20000 + b"o"
     + b")" * 20000 + b'"\n', "nested too deeply"),
])
def test_diagnose_locates_each_bad_model(tmp_path, capsys, name, content, expected):
    (tmp_path / name).write_bytes(content)
    (tmp_path / "obs.json").write_text(json.dumps({"o": 1}))
    err = run(capsys, "diagnose", str(tmp_path / name), "--obs", str(tmp_path / "obs.json"))
    assert expected in err.replace(str(tmp_path) + "/", "")


@pytest.mark.parametrize("content, expected", [
    (b'{"\xe9": 1}', "obs.json:1:3: this observations file is not UTF-8 text"),
    (b"[" * 100000 + b"]" * 100000, "obs.json: nested too deeply"),
])
def test_diagnose_locates_each_bad_observations_file(tmp_path, capsys, content, expected):
    (tmp_path / "obs.json").write_bytes(content)
    err = run(capsys, "diagnose", MODEL, "--obs", str(tmp_path / "obs.json"))
    assert expected in err.replace(str(tmp_path) + "/", "")
