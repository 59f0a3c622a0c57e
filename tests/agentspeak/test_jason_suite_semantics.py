"""Jason 3.3.2 behaviours that decide what Jason's own unit-test suite counts and when its timed tests
run (``make jason-tests``, issue 21); one test each, written from Jason's sources (cited per test)."""
from __future__ import annotations

import textwrap

from tests.agentspeak.harness import run_asl


def asl(text: str) -> str:
    return textwrap.dedent(text)


# -- a body term is "capplied" when stored (asSyntax/PlanBodyImpl.capply -> ArithFunctionTerm.capply) -----
def test_a_body_term_stored_in_a_belief_holds_its_functions_computed():
    # PlanBodyImpl.capply applies capply to each formula, and ArithFunctionTerm.capply computes a
    # function (.count allows unbound arguments): the stored term holds the count of that moment, so an
    # equal one added later is the same belief and posts no +stored event (Agent.addBel / BeliefBase.add)
    out = run_asl(asl("""
        b(1). b(2).
        !start.
        +!start <- +stored({ .print(.count(b(_))) }); +stored({ .print(1+1) }); +b(3);
                   +stored({ .print(.count(b(_)), X) }); .count(stored(_), N); .print(beliefs(N)).
        +stored(S) <- .print(event(S)).
    """))
    assert out == ["event({ .print(2) })", "event({ .print(3,X) })", "beliefs(2)"]


def test_a_body_term_keeps_what_cannot_be_computed_yet():
    # ArithFunctionTerm.capply: a function that does not allow unbound arguments (.length) stays as it is
    # until they are bound; an if's condition is code (it runs when the body runs)
    out = run_asl(asl("""
        !start.
        +!start <- +stored({ X = .length(L) }); +stored({ if (.length([a]) > 0) { .print(y) } });
                   .findall(S, stored(S), Ss); .print(Ss).
    """))
    assert out == ["[{ if ((.length([a]) > 0)) { .print(y) } },{ (X = .length(L)) }]"]
