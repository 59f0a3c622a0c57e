"""The compiled-formula cache (agentspeak/solver.py ``compiled``) stays bounded however many formulas an agent
makes while it runs (issue 22's soak), a formula evicted from it is compiled again, with the same answer, and one
still in use is never evicted, however many others come and go."""
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
    assert len(solver._COMPILED) <= LIMIT and len(solver._OLDER) <= LIMIT
    b: dict = {}
    assert solve_first(kb, first, b)     # evicted long ago: compiled again, same answer
    assert sorted(str(v) for v in b.values()) == ["1", "2"]


def test_a_formula_in_use_stays_compiled_while_others_come_and_go():
    """A program's formula used now and then is not compiled again because many formulas were made meanwhile (an
    oldest-out cache compiled it again after every LIMIT new ones, and a program of more formulas than that at every
    use)."""
    hot = And(Literal("encoders", (Var("L"), Var("R"))), Not(Literal("blocked", (Var("_"),))))
    first = solver.compiled(hot)
    for i in range(LIMIT * 3):
        solver.compiled(Not(Literal("blocked", (i,))))
        if i % 100 == 0:
            assert solver.compiled(hot) is first, i
