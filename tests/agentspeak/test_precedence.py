"""Operator precedence as Jason nests it: | < & < not < relational < + - < * / div mod < ** < unary minus."""
from __future__ import annotations

from agentspeak.parser import parse_program
from tests.agentspeak.harness import run_asl


def context_of(text: str) -> str:
    return str(parse_program(f"+!g : {text} <- true.").plans[0].context)


def test_not_binds_looser_than_relational_and_tighter_than_and_or() -> None:
    assert context_of("not X > 3 & not a | b & not not c") == \
        "((not ((X > 3)) & not (a)) | (b & not (not (c))))"


def test_arithmetic_precedence_and_right_associative_power() -> None:
    assert context_of("X = -Y + 2 * 3 ** 2 ** 1") == "(X = ((-Y)+(2*(3**(2**1)))))"


def test_not_of_a_comparison_is_evaluated_as_a_whole() -> None:
    lines = run_asl("""
        x(5).
        !g.
        +!g : x(X) & not X > 3 <- .print(wrong).
        +!g : x(X) & not X > 7 <- .print(right, " ", -X + 1, " ", 2 ** 3 ** 2).
    """)
    assert lines == ["right -4 512"]
