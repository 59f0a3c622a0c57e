"""Terms, numbers and printing as Jason 3.3.2 prints them (each test runs a program and compares lines)."""
from __future__ import annotations

import pytest

from tests.agentspeak.harness import run_asl


def body(text: str) -> list[str]:
    return run_asl(f"!t.\n+!t <- {text}.\n")


@pytest.mark.parametrize("expr, printed", [
    ("8/4", "2"),
    ("0.1+0.2", "0.30000000000000004"),
    ("1.0E20", "1.0E20"),
    ("1e-5", "1.0E-5"),
    ("7/2", "3.5"),
    ("2**10", "1024"),
    ("-7 div 2", "-3"),
    ("-7 mod 3", "-1"),
    ("7 mod -3", "1"),
    ("7.5 mod 2", "1.5"),
    ("100000000.0*100", "10000000000"),
    ("3.0", "3"),
    ("-(2+3)*2", "-10"),
    ("2**3**2", "512"),
])
def test_numbers_print_as_java_doubles(expr, printed):
    assert body(f"X = {expr}; .print(X)") == [printed]


def test_equality_of_int_and_double():
    assert body('if (3 == 3.0) { .print(same) } else { .print(differ) }') == ["same"]


def test_strings_top_level_unquoted_nested_quoted():
    assert body('.print("s", f(x,"s"), " ", [a,"b"])') == ['sf(x,"s") [a,"b"]']


def test_string_is_not_an_atom():
    assert body('if ("abc" \\== abc) { .print(distinct) }') == ["distinct"]


def test_unbound_variable_prints_no_value():
    assert body(".print(Y)") == ["Y<no-value>"]


def test_annotations_are_a_sorted_set():
    assert body(".print(p[b,c,10,b])") == ["p[10,b,c]"]


def test_lists_print_without_spaces_and_tails_join():
    assert body(".print([a, b | [c]], [], [1,[2, 3]])") == ["[a,b,c][][1,[2,3]]"]


def test_list_head_tail_unification():
    assert body("[H|T] = [1,2,3]; [A,B|R] = [x,y]; .print(H, T, A, B, R)") == ["1[2,3]xy[]"]


def test_strong_negation_belief_and_query():
    src = "~rain.\n!t.\n+!t : ~rain <- .print(dry); ?~rain; .print(still).\n"
    assert run_asl(src) == ["dry", "still"]


def test_quoted_atom_and_comments():
    src = "// line comment\n/* block\ncomment */ !t.\n+!t <- X = 'Hello World'; if (X == 'Hello World') { .print(eq) }.\n"
    assert run_asl(src) == ["eq"]


def test_univ_gives_namespace_functor_args_annots():
    assert body("p(1)[a] =.. L; .print(L); T =.. [q, [1,2], [b]]; .print(T)") == [
        "[default,p,[1],[a]]", "q(1,2)[b]"]


def test_relational_and_standard_order():
    assert body("if (1 < a & a < b & \"s\" < a & b < f(x) & a < b(1)) { .print(ordered) }") == ["ordered"]


def test_arithmetic_on_non_number_fails_the_plan():
    src = "!t.\n+!t <- Y = a; X = Y + 1; .print(X).\n-!t <- .print(failed).\n"
    assert run_asl(src) == ["failed"]


def test_atom_operand_parses_and_fails_with_a_clear_message():
    src = ("!t.\n+!t <- X = a + 1; .print(X).\n"
           "-!t[error(E), error_msg(M)] <- .print(E, \" \", M).\n")
    assert run_asl(src) == ["wrong_arguments arithmetic on a non-number: a in (a+1)"]


def test_plus_and_minus_after_an_atom_are_operators():
    assert body("X = 1; .print(b(X - 1), [X + 1]); if (X - 1 < 1) { .print(small) }") == ["b(0)[2]", "small"]


def test_unbound_operand_keeps_the_expression():
    assert body("X = Y + 1; .print(X)") == ["(Y+1)"]


def test_quoted_atoms_keep_their_quotes_as_in_jason():
    # Jason keeps the quotes in the functor: 'abc' prints quoted and is not the atom abc
    assert body(".print('quoted atom', \" \", f('A b'), \" \", 'abc', \" \", ~'x y'); "
                "if ('abc' \\== abc) { .print(distinct) }; .term2string('a b', S); .print(S)") == [
        "'quoted atom' f('A b') 'abc' ~'x y'", "distinct", "'a b'"]
