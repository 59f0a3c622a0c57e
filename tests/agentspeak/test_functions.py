"""Arithmetic functions (Jason's ``jason/functions``, item D6): one test per family, comparing the
printed lines exactly. Expected values follow Jason 3.3.2's documentation and Java's Math semantics."""
from __future__ import annotations

import pytest

from agentspeak.errors import AslSyntaxError
from agentspeak.parser import parse_program
from tests.agentspeak.harness import run_asl, run_asl_logged

FAIL_PLAN = "-!t[error(E), error_msg(M)] <- .print(E, \": \", M).\n"


def body(text: str, extra: str = "") -> list[str]:
    return run_asl(f"{extra}!t.\n+!t <- {text}.\n{FAIL_PLAN}")


def test_constants_and_trigonometry():
    assert body('.print(math.pi, " ", math.e); .print(math.sin(math.pi / 2), " ", math.cos(0), " ", '
                'math.tan(0), " ", math.atan(1) * 4 == math.pi, " ", math.acos(1), " ", math.asin(2))') == [
        "3.141592653589793 2.718281828459045", "1 1 0 (3.141592653589793 == 3.141592653589793) 0 NaN"]


def test_rounding_is_javas():
    assert body('.print(math.round(2.5), " ", math.round(-2.5), " ", math.round(1.1), " ", math.round(1.9), " ", '
                'math.round(0.49999999999999994), " ", math.floor(-3.5), " ", math.ceil(3.1), " ", '
                'math.abs(-1), " ", math.abs(-2.5))') == ["3 -2 1 2 0 -4 4 1 2.5"]


def test_sqrt_and_log_give_java_doubles_not_errors():
    assert body('.print(math.sqrt(9), " ", math.sqrt(2), " ", math.sqrt(-1), " ", math.log(0), " ", '
                'math.log(math.e), " ", math.log(-1))') == ["3 1.4142135623730951 NaN -Infinity 1 NaN"]


def test_max_and_min_of_two_numbers_or_of_a_list():
    # the list form skips non-numbers and starts from Double.MIN_VALUE / Double.MAX_VALUE as Jason does
    assert body('.print(math.max(3, 7), " ", math.min(3, 7), " ", math.max([3, a, "s", 5]), " ", '
                'math.min([3, a, "s", 5]), " ", math.max([-3, -5]), " ", math.min([]))') == [
        "7 3 5 3 4.9E-324 1.7976931348623157E308"]


def test_list_statistics():
    assert body('.print(math.sum([1, 3]), " ", math.sum([3, a, "s", 5]), " ", math.sum([]), " ", '
                'math.average([1, 2]), " ", math.average([]), " ", math.mean([1, 3]), " ", '
                'math.median([1, 3]), " ", math.median([3, 1, 1]), " ", math.std_dev([1, 2, 3]), " ", '
                'math.std_dev([2, 4, 4, 4, 5, 5, 7, 9]))') == ["4 8 0 1.5 NaN 2 2 1 1 2.138089935299395"]


def test_random_uses_the_seeded_generator_and_stays_in_range():
    assert body(".set_random_seed(7); A = math.random(10); .set_random_seed(7); B = math.random(10); "
                "C = math.random; .set_random_seed(8); D = math.random(10); "
                "if (A == B & A \\== D & A >= 0 & A < 10 & C >= 0 & C < 1) { .print(ok) } "
                "else { .print(A, \" \", B, \" \", C, \" \", D) }") == ["ok"]


def test_system_time_is_milliseconds_since_the_epoch():
    out = body('T1 = system.time; .wait(20); T2 = system.time; '
               'if (T2 - T1 >= 15 & T1 > 1600000000000) { .print(ok) } else { .print(T1, " ", T2) }')
    assert out == ["ok"]


def test_count_and_length_as_functions_in_contexts_rules_and_arguments():
    src = ("b(1). b(5). b(7).\n"
           "big(N) :- N = .count(b(X) & X > 2).\n"
           "!t.\n"
           "+!t : .count(b(_)) > 2 & big(B) <- .print(B, \" \", .count(b(_)) * 2 + .length([a, b]), \" \", "
           ".length(\"abcd\"), \" \", .count(c(_))).\n")
    assert run_asl(src) == ["2 8 4 0"]


def test_functions_in_beliefs_goals_conditions_and_loops():
    assert body("+n(math.round(2.7)); ?n(N); .print(N); !g(math.max(1, 4)); "
                "for (.member(X, [1, 5, 9]) & X < math.sqrt(49)) { .print(X) }; "
                "if (n(math.floor(3.9))) { .print(yes) }",
                extra="+!g(X) <- .print(g(X)).\n") == ["3", "g(4)", "1", "5", "yes"]


def test_user_functions_from_rules_and_internal_actions():
    src = ('{ register_function("myf.sum", 2, "sum") }\n'
           "sum(X, Y, S) :- S = X + Y.\n"
           '{ register_function("myf.limit", 0, "limit") }\n'
           "limit(10).\n"
           '{ register_function("my.len", 1, ".length") }\n'
           "h(State, Goal, H) :- H = math.abs(Goal - State).\n"
           '{ register_function("search.h", 2, "h") }\n'
           "!t.\n"
           "+!t <- .print(myf.sum(1, 2), \" \", myf.limit, \" \", myf.sum(5, myf.sum(2, myf.limit)), \" \", "
           "my.len([a, b, c]), \" \", search.h(10, 3)).\n")
    assert run_asl(src) == ["3 10 17 3 7"]


def test_wrong_arguments_fail_the_plan_with_an_error_annotation():
    assert body("X = math.abs(a)") == ["wrong_arguments: math.abs(a): the argument 'a' is not a number"]
    assert body("X = math.abs(Y)") == ["wrong_arguments: (X = math.abs(Y)): a function argument is unbound"]
    assert body("X = math.mean([])") == ["wrong_arguments: math.mean([]): no numbers to take the mean of"]
    assert body("X = math.median([1, a])") == [
        "wrong_arguments: math.median([1,a]): the list has a non-number, 'a'"]
    assert body(".print(.length(a))") == ["wrong_arguments: .length(a): 'a' is not a list or a string"]


def test_context_error_makes_the_plan_not_applicable(caplog):
    src = "!t.\n+!t : math.abs(a) > 1 <- .print(first).\n+!t <- .print(second).\n"
    out, warnings = run_asl_logged(src, caplog)
    assert out == ["second"]
    assert any("math.abs(a)" in w for w in warnings)


def test_other_arities_are_not_functions():
    # Jason's parser makes a function only when the arity is one the function accepts
    assert body("X = math.max(1, 2, 3); .print(X)") == ["math.max(1,2,3)"]


def test_bad_register_function_directive_is_a_warning(caplog):
    src = ('{ register_function("nodot", 1, "p") }\n{ register_function("myf.C") }\n'
           "!t.\n+!t <- .print(ok).\n")
    out, warnings = run_asl_logged(src, caplog)
    assert out == ["ok"]
    assert any("nodot" in w and ":1:" in w for w in warnings)
    assert any("Java class" in w and ":2:" in w for w in warnings)


def test_bad_function_argument_in_a_belief_is_a_load_error_with_file_and_line():
    with pytest.raises(AslSyntaxError) as info:
        parse_program("b(1).\np(math.abs(a)).\n", "f.asl")
    assert (info.value.file, info.value.line) == ("f.asl", 2)
    assert "math.abs(a): the argument 'a' is not a number" in str(info.value)


def test_a_function_registered_after_a_parse_is_seen_by_the_next_parse_of_the_same_text():
    # parse_program caches programs by text; `ns.f(...)` is a call only if ns.f is registered, so a
    # later registration must not be met by the earlier, cached parse
    from agentspeak.terms import Func
    from agentspeak.stdlib.registry import FUNCTIONS

    src = "+!g <- X = latecomer.triple(2).\n"
    before = parse_program(src, "late.asl")
    FUNCTIONS.arith_function("latecomer.triple", args=1)(lambda x: 3 * x)
    try:
        after = parse_program(src, "late.asl")
    finally:
        FUNCTIONS.functions.pop("latecomer.triple", None)
    assert type(before.plans[0].body[0].term.right) is not Func
    assert type(after.plans[0].body[0].term.right) is Func


def test_a_rule_function_of_unbound_arguments_waits_until_they_are_bound():
    """Jason's capply leaves a function it cannot compute yet as it is: a rule function in a .findall
    query inside a rule is computed per solution (Jason's demos/search, a_star.asl)."""
    src = ('{ register_function("my.h", 2, "h") }\n'
           'h(S, G, H) :- H = math.abs(G - S).\n'
           'q(L) :- .findall(N, (.member(S, [1, 2]) & N = my.h(S, 9) + 0), L).\n'
           '!g.\n'
           '+!g <- ?q(L); .print(L).\n')
    assert run_asl(src) == ["[8,7]"]
