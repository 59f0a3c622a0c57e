"""``faultmas asl check`` knows the internal actions an agent can run: unknown names and wrong arities (issue 23)."""
from __future__ import annotations

from pathlib import Path

from agents.cli import main

PLANS = Path(__file__).resolve().parents[2] / "plans"

BAD = """!start.
+!start : .member(X, [1,2]) <- .print("hi"); .wait(1, 2, 3, 4); .diagnos(m, [], D).
+!g <- if (.lenght([1], N)) { .print(N) }; for (.member(Y, [1])) { .my_nam(Y) }.
r(X) :- .my_name(X) & .concat("a", "b", X, Y, Z, W, V) & .nonsense.
+!cnp <- !call. { +!call <- .df_serch("p", L). }
"""


def test_unknown_internal_actions_and_wrong_arities_fail_the_check(tmp_path: Path, capsys) -> None:
    source = tmp_path / "bad.asl"
    source.write_text(BAD)
    assert main(["asl", "check", str(source)]) == 2
    err = capsys.readouterr().err
    assert f"{source}:2: .wait takes 1 to 3 arguments, not 4" in err
    assert f"{source}:2: unknown internal action .diagnos/3; did you mean .diagnose?" in err   # a plug-in's
    assert f"{source}:3: unknown internal action .lenght/2; did you mean .length?" in err       # in an if
    assert f"{source}:3: unknown internal action .my_nam/1" in err                              # in a for body
    assert f"{source}:5: unknown internal action .df_serch/2; did you mean .df_search?" in err   # a sub-plan
    assert f"{source}:4: unknown internal action .nonsense/0" in err                             # in a rule
    assert ".member" not in err and ".print" not in err and ".my_name/" not in err


def test_the_shipped_plans_pass_the_check(capsys) -> None:
    files = [str(p) for p in sorted(PLANS.glob("*.asl"))]
    assert main(["asl", "check", *files]) == 0, capsys.readouterr().err


def test_mas2j_syntax_errors_say_what_was_expected_in_words(tmp_path: Path, capsys) -> None:
    project = tmp_path / "bad.mas2j"
    project.write_text('MAS m {\n  agents: a a.asl [beliefs="x"] foo;\n}\n')
    assert main(["asl", "check", str(project)]) == 2
    err = capsys.readouterr().err
    assert f"{project}:2:33: unexpected 'foo'; expected '#', ';', 'agentArchClass'" in err
    assert "HASH" not in err and "SEMICOLON" not in err and "LSQB" not in err
