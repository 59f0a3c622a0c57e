"""diagnosis/sat.py: Glucose 4 through python-sat's extension answers exactly as ``pysat.solvers.Glucose4`` does."""
from __future__ import annotations

import random
import subprocess
import sys

from pysat.solvers import Glucose4 as PysatGlucose4

from diagnosis.sat import Glucose4, make_solver


def _random_cnf(rng: random.Random, variables: int, clauses: int) -> list[list[int]]:
    return [[rng.choice((1, -1)) * rng.randint(1, variables) for _ in range(3)] for _ in range(clauses)]


def test_same_answers_models_and_cores_as_pysat() -> None:
    rng = random.Random(23)
    for _ in range(40):
        cnf = _random_cnf(rng, 12, rng.randint(20, 60))
        ours, theirs = Glucose4(cnf), PysatGlucose4(bootstrap_with=cnf)
        try:
            for _ in range(5):
                assumptions = [rng.choice((1, -1)) * v for v in rng.sample(range(1, 13), 4)]
                assert ours.solve(assumptions) == theirs.solve(assumptions=assumptions)
                assert ours.get_model() == theirs.get_model()
                assert ours.get_core() == theirs.get_core()
        finally:
            ours.delete()
            theirs.delete()


def test_clauses_added_later_phases_and_a_limited_solve() -> None:
    with Glucose4([[1, 2]]) as solver:
        solver.set_phases([-1, -2])
        assert solver.solve() is True and solver.get_model()[:2] in ([1, -2], [-1, 2])
        solver.add_clause((-1,))
        solver.append_formula([(-2, 3)])
        assert solver.solve_limited(expect_interrupt=True) is True
        assert solver.get_model()[:3] == [-1, 2, 3]
        assert solver.solve([-3]) is False and solver.get_core() == [-3] and solver.get_model() is None
        solver.interrupt()            # an interrupt asked for between calls ...
        solver.clear_interrupt()      # ... and taken back: the next call runs as usual
        assert solver.solve_limited([3], expect_interrupt=True) is True


def test_an_empty_clause_makes_the_formula_unsatisfiable() -> None:
    with Glucose4([[1], [-1]]) as solver:
        assert solver.solve() is False


def test_other_solvers_come_from_pysat() -> None:
    solver = make_solver("minisat22", [[1], [-1, 2]])
    try:
        assert type(solver).__module__ == "pysat.solvers"
        assert solver.solve() is True and solver.get_model() == [1, 2]
    finally:
        solver.delete()
    assert type(make_solver("glucose4")) is Glucose4


def test_the_glucose_route_does_not_import_pysat_solvers() -> None:
    """What the module is for (issue 23): ``pysat.solvers`` and ``pysat.formula`` stay unloaded."""
    code = ("import sys\nfrom diagnosis.sat import make_solver\ns = make_solver('glucose4', [[1, 2], [-1]])\n"
            "assert s.solve() and s.get_model() == [-1, 2]\n"
            "print(sorted(m for m in sys.modules if m.startswith('pysat')))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
