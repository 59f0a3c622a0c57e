"""The compiled-formula cache (agentspeak/solver.py ``compiled``) stays bounded however many formulas an agent
makes while it runs (issue 22's soak), and a formula evicted from it is compiled again, with the same answer."""
from __future__ import annotations

from agentspeak import solver
from agentspeak.agent import Agent
from agentspeak.solver import solve_first
from agentspeak.terms import And, Literal, Not, Var


LIMIT = getattr(solver, "COMPILED_LIMIT", 2048)


def test_formulas_made_at_run_time_do_not_pile_up_in_the_cache():
    kb = Agent("robot1")
    kb.bb.add(Literal("encoders", (1, 2)))
    first = And(Literal("encoders", (Var("L"), Var("R"))), Not(Literal("blocked", (Var("_"),))))
    assert solve_first(kb, first, {})
    for i in range(LIMIT * 2):   # a new formula object each time, as a question or a copy is
        formula = And(Literal("encoders", (Var("L"), Var("R"))), Not(Literal("blocked", (i,))))
        assert solve_first(kb, formula, {})
    assert len(solver._COMPILED) <= LIMIT
    b: dict = {}
    assert solve_first(kb, first, b)     # evicted long ago: compiled again, same answer
    assert sorted(str(v) for v in b.values()) == ["1", "2"]
