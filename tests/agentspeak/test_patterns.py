"""Jason's goal-pattern directives (``{ begin dg(g) } ... { end }``), written from Jason 3.3.2's
``jason.asSyntax.patterns.goal`` (DG, BDG, EBDG, BC, SMC, RC, OMC, MG, SGA) and the Jason book, ch. 8."""
from __future__ import annotations

import textwrap

import pytest

from agentspeak.errors import AslSyntaxError
from agentspeak.parser import parse_program
from tests.agentspeak.harness import run_asl


def asl(text: str) -> str:
    return textwrap.dedent(text).strip() + "\n"


def test_dg_adds_its_plans_around_the_goals_plans():
    program = parse_program(asl("""
        { begin dg(at(home)) }
        +!at(home) <- go.
        { end }
    """), "p.asl")
    assert [str(p) for p in program.plans] == [
        "+!at(home) : at(home)", "+!at(home) : .intend(at(home))",
        "+!at(home) <- go; ?at(home)", "+at(home) <- .succeed_goal(at(home))"]
    assert {p.line for p in program.plans} == {1, 2}  # the plans it adds say where the directive is


def test_dg_a_goal_already_believed_needs_no_plan_and_is_achieved_once_believed():
    out = run_asl(asl("""
        at(work).
        !at(work).
        !at(home).
        { begin dg(at(W)) }
        +!at(W) <- .print(going, W); +at(W); .print(never).
        { end }
    """))
    assert out == ["goinghome"]


def test_dg_a_plan_that_ends_without_the_goal_believed_fails_the_goal():
    out = run_asl(asl("""
        !clean.
        { begin dg(clean) }
        +!clean <- .print(tried).
        { end }
        -!clean <- .print(not_clean).
    """))
    assert out == ["tried", "not_clean"]


def test_bdg_tries_again_until_the_goal_is_believed():
    out = run_asl(asl("""
        n(0).
        !clean.
        { begin bdg(clean) }
        +!clean : n(N) & N < 2 <- -+n(N + 1); .print(try, N).
        +!clean <- .print(done); +clean.
        { end }
    """))
    assert out == ["try0", "try1", "done"]


def test_ebdg_tries_each_plan_once():
    out = run_asl(asl("""
        !clean.
        { begin ebdg(clean) }
        +!clean <- .print(first).
        +!clean <- .print(second); +clean.
        { end }
    """))
    assert out == ["first", "second"]


def test_mg_believes_the_goal_and_restores_it_when_it_is_lost():
    out = run_asl(asl("""
        !spill.
        +!spill <- .wait(20); -tidy; .wait(100); if (tidy) { .print(tidy_again) }.
        { begin mg(tidy) }
        +!tidy <- .print(tidying); +tidy.
        { end }
    """))
    assert out == ["tidying", "tidy_again"]


def test_smc_drops_the_goal_when_the_failure_condition_is_believed():
    # +broken <- .fail_goal(g): the attempt in progress is abandoned; bdg's -!g <- !g tries again
    out = run_asl(asl("""
        !top.
        !break.
        +!top <- !g; .print(after).
        { begin smc(g, broken) }
        +!g : not tried <- +tried; .wait(1000); .print(never).
        +!g <- .print(again); +g.
        { end }
        +!break <- .wait(50); +broken.
    """))
    assert out == ["again", "after"]


def test_sga_adopts_goals_one_at_a_time():
    out = run_asl(asl("""
        { begin sga("+job(J)", "true", do(J)) }
        { end }
        +!do(J) <- .print(start, J); .wait(30); .print(end, J).
        !go.
        +!go <- +job(1); +job(2).
    """))
    assert out == ["start1", "end1", "start2", "end2"]


@pytest.mark.parametrize("text, line, message", [
    ("{ begin namespace(x, private) }\nb.\n{ end }\n", 1, "must be local or global"),
    ("{ begin namespace(x) }\nb.\n", 1, "has no '{ end }'"),
    ("b.\n{ begin logger }\n{ end }\n", 2, "unknown directive"),
    ("{ begin dg(a) }\nb.\n", 1, "has no '{ end }'"),
    ("b.\n{ end }\n", 2, "without a '{ begin"),
    ("{ begin dg(a, b) }\n{ end }\n", 1, "takes 1 argument"),
    ("{ begin dg(X) }\n{ end }\n", 1, "must be a literal"),
])
def test_a_directive_that_cannot_be_applied_is_a_located_error(text, line, message):
    with pytest.raises(AslSyntaxError) as exc:
        parse_program(text, "p.asl")
    assert message in str(exc.value) and exc.value.line == line
