"""The shared watchdog interrupts a real SAT call at its deadline and leaves the solver usable."""
from __future__ import annotations

import itertools

from pysat.solvers import Solver

from diagnosis.deadline import Deadline


def pigeonhole(holes: int) -> list[list[int]]:
    """holes + 1 pigeons in `holes` holes: unsatisfiable and hard for CDCL."""
    var = lambda p, h: p * holes + h + 1  # noqa: E731
    clauses = [[var(p, h) for h in range(holes)] for p in range(holes + 1)]
    for h in range(holes):
        clauses += [[-var(p, h), -var(q, h)] for p, q in itertools.combinations(range(holes + 1), 2)]
    return clauses


def test_watchdog_interrupts_and_release_clears_the_interrupt():
    with Solver(name="glucose4", bootstrap_with=pigeonhole(11)) as solver:
        deadline = Deadline(0.2).watch(solver)
        assert solver.solve_limited(expect_interrupt=True) is None   # cut off, not decided
        assert deadline.expired()
        deadline.release(solver)
        assert solver.solve_limited(assumptions=[1, -1], expect_interrupt=True) is False  # usable again
        both = [Deadline(30.0).watch(solver), Deadline(0.1).watch(solver)]  # the nearer one fires first
        assert solver.solve_limited(expect_interrupt=True) is None
        assert not both[0].expired() and both[1].expired()
        for d in both:
            d.release(solver)
