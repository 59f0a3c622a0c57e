"""The formula grammar, its error messages, and the clausification (checked against truth tables)."""
from __future__ import annotations

import itertools

import pytest
from hypothesis import given, settings, strategies as st

from diagnosis.formula import Ab, Atom, FormulaSyntaxError, evaluate, literals, parse_formula, to_cnf


def test_precedence_and_right_associative_implication():
    f = parse_formula("a | b & c -> d -> e")
    # (a | (b & c)) -> (d -> e)
    vals = {Atom(n): False for n in "abcde"}
    assert evaluate(f, vals)  # antecedent false
    vals.update({Atom("a"): True, Atom("d"): True})
    assert not evaluate(f, vals)


def test_ab_literals_and_applied_atoms_keep_canonical_names():
    f = parse_formula("!timing( scan , pose ) -> AB(amcl) | ~AB(/scan)")
    assert literals(f) == [Atom("timing(scan,pose)"), Ab("amcl"), Ab("/scan")]


@pytest.mark.parametrize("text, column, fragment", [
    ("a &", 4, "ends too early"),
    ("a -> -> b", 6, "unexpected '->'"),
    ("(a", 3, "expected ')'"),
    ("a ? b", 3, "unexpected '?'"),
    ("AB(x, y)", 1, "AB takes one component"),
])
def test_syntax_errors_give_column_and_reason(text, column, fragment):
    with pytest.raises(FormulaSyntaxError) as info:
        parse_formula(text)
    assert info.value.column == column
    assert fragment in str(info.value)


NAMES = ["p", "q", "r", "AB(c)"]
leaf = st.sampled_from(NAMES + ["true", "false"])
formula_text = st.recursive(leaf, lambda sub: st.one_of(
    st.builds(lambda a: f"!({a})", sub),
    st.builds(lambda a, b, op: f"({a}) {op} ({b})", sub, sub, st.sampled_from(["&", "|", "->", "<->"]))),
    max_leaves=8)


@settings(max_examples=150, deadline=None)
@given(formula_text)
def test_cnf_is_satisfiable_exactly_when_the_formula_is_true(text):
    """For every assignment of the formula's atoms, the CNF (with its auxiliary variables free) is
    satisfiable exactly when the formula is true. Satisfiability is asked of a SAT solver under the
    assignment as assumptions: enumerating the auxiliary variables by hand took hours on a formula with
    twenty of them (2^20 assignments), which hypothesis draws now and then."""
    from pysat.solvers import Solver

    f = parse_formula(text)
    lits = [Atom("p"), Atom("q"), Atom("r"), Ab("c")]
    var = {l: i + 1 for i, l in enumerate(lits)}
    counter = itertools.count(len(lits) + 1)
    clauses = to_cnf(f, var.__getitem__, lambda: next(counter))
    with Solver(name="minisat22", bootstrap_with=clauses) as solver:
        for bits in itertools.product([False, True], repeat=len(lits)):
            values = dict(zip(lits, bits))
            expected = evaluate(f, values)
            sat = solver.solve(assumptions=[var[l] if b else -var[l] for l, b in values.items()])
            assert sat == expected, (text, values)
