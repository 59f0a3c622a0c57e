"""Standard internal actions: lists, strings, queries, system, .wait forms."""
from __future__ import annotations

import pytest

from tests.agentspeak.harness import run_asl


def body(text: str, extra: str = "") -> list[str]:
    return run_asl(f"{extra}!t.\n+!t <- {text}.\n-!t[error(E)] <- .print(failed, E).\n")


@pytest.mark.parametrize("call, printed", [
    ('.concat([a],[b,c],R); .print(R)', "[a,b,c]"),
    ('.concat("ab", "cd", 1, R); .print(R)', "abcd1"),
    ('.length([1,2,3], N); .length("hello", M); .print(N, M)', "35"),
    ('.nth(1, [a,b,c], X); .print(X)', "b"),
    ('.member(b, [a,b]); .print(yes)', "yes"),
    ('.member(X, [a,b]); .print(X)', "a"),           # a generator action binds (compiled build too)
    ('.member(z, [a,b])', "failedia_failed"),        # ... and fails when it has no solution
    ('.reverse([1,2,3], R); .print(R)', "[3,2,1]"),
    ('.delete(a, [a,b,a], R); .print(R)', "[b]"),
    ('.delete(0, [a,b], R); .print(R)', "[b]"),
    ('.sort([c, 1, b(1), a, 0.5], S); .print(S)', "[0.5,1,a,c,b(1)]"),
    ('.max([3,1,4], X); .min([3,1,4], Y); .print(X, Y)', "41"),
    ('.sum([1,2,3.5], S); .print(S)', "6.5"),
    ('.empty([]); .print(empty)', "empty"),
    ('.findall(X, .member(X,[c,a]), L); .print(L)', "[c,a]"),
    ('.setof(X, .member(X,[c,a,b,a]), L); .print(L)', "[a,b,c]"),
    ('.count(.member(_,[a,b,c]), N); .print(N)', "3"),
    ('.term2string(f(x,"a"), S); .print(S); .term2string(T, "g(1,b)"); .print(T)', 'f(x,"a")'),
    ('.string("x"); .substring("bc", "abcd", P); .print(P)', "1"),
    ('.substring("bc", "abcd"); .print(in); .substring("x", "abc")', "in"),
    ('.findall(P, .substring("a", "banana", P), L); .print(L)', "[1,3,5]"),
    ('.findall(R, .random(R, 3), L); .length(L, N); .print(N)', "3"),
    ('.lower_case("AbC", L); .upper_case("AbC", U); .print(L, U)', "abcABC"),
    ('.replace("aXbX", "X", "y", R); .print(R)', "ayby"),
    ('.my_name(N); .print(N)', "ag"),
    ('.random(R); if (R >= 0 & R < 1) { .print(in_range) }', "in_range"),
    ('.time(H,M,S); .date(Y,Mo,D); if (H < 24 & Mo <= 12 & Y > 2000) { .print(ok) }', "ok"),
    ('.nth(5, [a], X)', "failedia_failed"),
    ('.length(1, 2, 3)', "failedwrong_arguments"),
])
def test_internal_action(call, printed):
    assert body(call)[0] == printed


def test_term2string_both_directions():
    assert body('.term2string(f(x,"a"), S); .print(S); .term2string(T, "g(1,b)"); .print(T)') == [
        'f(x,"a")', "g(1,b)"]


def test_println_is_print():
    assert body('.println("a", 1, b)') == ["a1b"]


def test_abolish_removes_all_matching():
    assert body(".abolish(b(_)); .count(b(_), N); .print(N)", "b(1). b(2). c.\n") == ["0"]


def test_wait_forms():
    src = """!main.
+!main <- !!w; .wait({+go}); .print(gone); .wait(flag); .print(flagged);
   .wait({+never}, 30, E); .print(three_arg_continues);
   .wait({+never}, 30).
+!w <- .print(w1); +go; .print(w2); +flag.
-!main[error(E)] <- .print(two_arg_fails).
"""
    assert run_asl(src) == ["w1", "gone", "w2", "flagged", "three_arg_continues", "two_arg_fails"]


def test_an_event_after_a_wait_timed_out_resumes_nothing():
    """A ``.wait({+go}, T)`` that timed out must stop waiting: a later ``+go`` once "resumed" the finished
    intention (an IndexError that killed an agent process when the event came in a message)."""
    src = """!main. !other. !later.
+!main <- .wait({+go}, 30, E); .print(continued).
+!other <- .wait({+go}, 30); .print(never).
-!other <- .print(timed_out).
+!later <- .wait(200); +go; .print(still_running).
"""
    assert sorted(run_asl(src)) == ["continued", "still_running", "timed_out"]


def test_wait_milliseconds():
    assert body(".wait(20); .print(after)") == ["after"]


def test_stop_mas_stops_other_intentions():
    src = "!a. !b.\n+!a <- .print(a); .stopMAS.\n+!b <- .wait(3000); .print(never).\n"
    assert run_asl(src, timeout=10) == ["a"]


def test_include_at_run_time(tmp_path):
    lib = tmp_path / "lib.asl"
    lib.write_text("+!hi <- .print(hi_from_lib).\n")
    assert body(f'.include("{lib}"); !hi') == ["hi_from_lib"]


def test_remove_plan_term_by_label_and_unlabelled_fails_as_in_jason():
    # `-{...}` is Jason's .remove_plan(plan term): it removes by label; without a label Jason's
    # .remove_plan fails the goal (ia_failed)
    src = ("!t.\n"
           "+!t <- +{ @p1 +!g <- .print(one) }; !g; -{ @p1 +!g <- .print(one) }; "
           ".relevant_plans({+!g}, L); .print(L); +{ +!h <- .print(h) }; -{ +!h <- .print(h) }; .print(after).\n"
           "-!t[error(E)] <- .print(failed, E); .relevant_plans({+!h}, L); .length(L, N); .print(N).\n")
    assert run_asl(src) == ["one", "[]", "failedia_failed", "1"]


def test_remove_plan_action_takes_a_plan_term_or_a_label_string():
    assert body('+{ @q1 +!k <- true }; +{ @q2 +!k <- true }; .remove_plan({ @q1 +!k <- true }); '
                '.remove_plan("@q2"); .relevant_plans({+!k}, L); .print(L)') == ["[]"]


# -- Jason 3.3.2 actions added for the remaining stdlib (jason.stdlib.save_agent, get_src_info,
#    internal_action; their Javadoc is the reference) --------------------------------------------
def test_save_agent_writes_beliefs_rules_goals_and_plans_that_load_again(tmp_path):
    path = tmp_path / "saved.asl"
    out = run_asl(f"""
        price(tv, 10)[from(shop)].
        cheap(X) :- price(X, P) & P < 20.
        !save.
        +!save <- +seen(1); .save_agent("{path}", [go, say(hello)]); .print(saved).
        +!go : cheap(tv) & seen(N) <- .print(cheap, N).
        +!say(W) <- .print(W).
        +!bids <: false <- .wait(10). {{ +offer(V) <- .done. }}
    """)
    assert out == ["saved"]
    text = path.read_text()
    assert "price(tv,10)[from(shop)]." in text and "source(self)" not in text.split("// plans")[0]
    assert "!go.\n!say(hello)." in text and "<: false" in text and "+offer(V)" in text
    # the saved agent is a program that runs: its beliefs, rules, goals and plans came along
    assert run_asl(text) == ["cheap1", "hello"]


def test_save_agent_to_a_folder_that_does_not_exist_fails_with_the_reason(tmp_path):
    out = run_asl(f"""
        !s.
        +!s <- .save_agent("{tmp_path}/no/such/x.asl").
        -!s[error_msg(M)] <- .print(M).
    """)
    assert len(out) == 1 and "cannot write" in out[0] and "No such file" in out[0]


def test_internal_action_tells_internal_action_terms_apart():
    out = run_asl("""
        !t.
        +!t <- for (.member(T, [.print(a), kk.tt(1), print(a), "s", 1, math.abs(1)])) {
                  if (.internal_action(T)) { .print(yes) } else { .print(no) }
               }.
    """)
    assert out == ["yes", "yes", "no", "no", "no", "no"]


def test_get_src_info_annotates_a_literal_with_where_it_is_written():
    out = run_asl("""
        !t.
        +!t <- .get_src_info(p(1), L);
               .print(L);
               .get_src_info(q[code_line(7)], M); .print(M).
    """)
    # line 3: run_asl's source starts with a newline; annotations sort as Jason sorts them
    assert out == ['p(1)[code_line(3),code_src("<string>")]', 'q[code_line(7),code_src("<string>")]']
