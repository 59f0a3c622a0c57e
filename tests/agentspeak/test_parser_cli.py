"""Parse errors (file:line:col, caret, expected) and the `faultmas asl check|run` / `mas run` commands."""
from __future__ import annotations

import subprocess
import sys

import pytest

from agentspeak.errors import AslSyntaxError
from agentspeak.parser import parse_program, parse_program_all_errors

CLI = [sys.executable, "-m", "agents.cli"]


@pytest.mark.parametrize("source, line, col, words", [
    ('!g.\n+!g <- .print("abc).\n', 2, 15, "unclosed string"),
    ("!g.\n+!g <- .print(a)\n+!h <- true.\n", 3, 1, "missing '.'"),
    ("b(1).\n+!g <- .print(a)) .\n", 2, 17, "expected"),
    ("b(1)\n", 1, 5, "missing '.'"),
])
def test_parse_errors_name_file_line_column_and_expectation(source, line, col, words):
    with pytest.raises(AslSyntaxError) as info:
        parse_program(source, "f.asl")
    err = info.value
    assert (err.file, err.line) == ("f.asl", line)
    if col is not None:
        assert err.column == col
        assert str(err).splitlines()[2].strip() == "^"
    assert words in str(err)


def test_all_errors_are_reported():
    _, errors = parse_program_all_errors('+!g <- .print("abc).\n+!h <- .print(a)) .\n+!k <- true.\n', "f.asl")
    assert [e.line for e in errors] == [1, 2]


def test_no_error_for_valid_program():
    program, errors = parse_program_all_errors("b(1).\n!g.\n+!g : .member(X, [1]) <- .print(X).\n", "f.asl")
    assert errors == [] and len(program.plans) == 1


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("asl")
    (d / "good.asl").write_text('!g.\n+!g <- .print(hi); .print("x", 1); !fail.\n+!fail <- .fail.\n')
    (d / "bad1.asl").write_text('!g.\n+!g <- .print("abc).\n')
    (d / "bad2.asl").write_text("!g.\n+!g <- .print(a)\n+!h <- true.\n")
    (d / "b.asl").write_text("!hi.\n+!hi <- .my_name(N); .print(N).\n")
    (d / "c.asl").write_text("!s.\n+!s : v(X) & w <- .print(v, X).\n")
    (d / "t.mas2j").write_text('MAS t {\n agents: b #3; c [beliefs="v(7),w"];\n}\n')
    return d


def _run(*args):
    return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True, timeout=60)


def test_check_reports_every_file_error_and_exits_2(files):
    r = _run("asl", "check", files / "bad1.asl", files / "good.asl", files / "bad2.asl")
    assert r.returncode == 2
    assert "bad1.asl:2:15" in r.stderr and "bad2.asl:3:1" in r.stderr
    assert r.stdout.count(": ok") == 1


def test_check_ok_exits_0(files):
    assert _run("asl", "check", files / "good.asl").returncode == 0


def test_run_prints_one_line_per_print_and_warnings_to_stderr(files):
    r = _run("asl", "run", files / "good.asl", "--name", "zz", "--timeout", "10")
    assert (r.returncode, r.stdout.splitlines()) == (0, ["[zz] hi", "[zz] x1"])
    assert "+!fail" in r.stderr


def test_run_parse_error_exits_2(files):
    r = _run("asl", "run", files / "bad2.asl")
    assert r.returncode == 2 and "bad2.asl:3:1" in r.stderr and r.stdout == ""


def test_mas_run_instances_and_beliefs_option(files):
    r = _run("mas", "run", files / "t.mas2j", "--timeout", "10")
    assert r.returncode == 0
    assert sorted(r.stdout.splitlines()) == ["[b1] b1", "[b2] b2", "[b3] b3", "[c] v7"]


def test_mas_run_cut_by_its_timeout_exits_124_as_with_processes(tmp_path):
    (tmp_path / "w.asl").write_text("!w.\n+!w <- .print(waiting); .wait(60000).\n")
    (tmp_path / "w.mas2j").write_text("MAS w { agents: w w.asl; }\n")
    r = _run("mas", "run", tmp_path / "w.mas2j", "--timeout", "1")
    assert (r.returncode, r.stdout.splitlines()) == (124, ["[w] waiting"])
