"""Reasoning cycle: interleaving, initial beliefs/goals, body formulas, control statements, TRO."""
from __future__ import annotations

from tests.agentspeak.harness import run_asl


def test_two_initial_goals_interleave_round_robin():
    src = """!a(0). !b(0).
+!a(N) : N < 3 <- .print(a,N); !a(N+1).
+!a(_).
+!b(N) : N < 3 <- .print(b,N); !b(N+1).
+!b(_).
"""
    assert run_asl(src) == ["a0", "b0", "a1", "b1", "a2", "b2"]


def test_atomic_plan_is_not_interleaved():
    src = """!a. !b.
@[atomic] +!a <- .print(a1); .print(a2); .print(a3).
+!b <- .print(b1); .print(b2).
"""
    assert run_asl(src) == ["a1", "a2", "a3", "b1", "b2"]


def test_initial_beliefs_post_events_before_initial_goals():
    src = "b(1). b(2).\n!g.\n+b(X) <- .print(b, X).\n+!g <- .print(g).\n"
    assert run_asl(src) == ["b1", "b2", "g"]


def test_subgoal_returns_bindings_and_new_focus_continues_at_once():
    src = """!g.
+!g <- !h(X); .print(got, X); !!k; .print(after_k).
+!h(5).
+!k <- .print(k).
"""
    assert run_asl(src) == ["got5", "after_k", "k"]


def test_belief_additions_and_update():
    src = """!g.
+!g <- +b(1); +>b(2); +<b(0); .findall(X, b(X), L); .print(L);
   -b(1); .findall(X, b(X), L2); .print(L2);
   -+c(1); -+c(2); .findall(Y, c(Y), L3); .print(L3);
   -nothere; .print(silent).
"""
    assert run_asl(src) == ["[0,1,2]", "[0,2]", "[2]", "silent"]


def test_body_belief_event_runs_for_new_beliefs_only():
    src = "!g.\n+!g <- +b; +b; .print(done).\n+b <- .print(added).\n"
    assert run_asl(src) == ["added", "done"]


def test_rules_and_test_goals():
    src = """b(1). b(2). b(3).
big(X) :- b(X) & X > 1.
fact(0, 1).
fact(N, F) :- N > 0 & fact(N-1, F1) & F = N * F1.
!g.
+!g <- ?big(Y); .print(Y); ?fact(5, F); .print(F); ?b(Z)[source(S)]; .print(Z, S).
"""
    assert run_asl(src) == ["2", "120", "1self"]


def test_test_goal_uses_belief_base_before_plan_then_plan_then_fails():
    src = """v(1).
!g.
+!g <- ?v(X); .print(bb, X); ?w(Y); .print(plan, Y); ?z.
+?v(X) <- X = 99.
+?w(7).
-!g[error(E)] <- .print(E).
"""
    assert run_asl(src) == ["bb1", "plan7", "test_goal_failed"]


def test_if_elif_else_while_for():
    src = """!g.
+!g <- N = 3;
   if (N > 5) { .print(big) } elif (N > 2) { .print(mid) } else { .print(small) };
   if (N > 9) { .print(no) };
   -+i(0); while (i(I) & I < 3) { .print(w, I); -+i(I+1) };
   for (.member(E, [x,y,z])) { .print(E) };
   for (.range(K, 1, 3)) { .print(K) }.
"""
    assert run_asl(src) == ["mid", "w0", "w1", "w2", "x", "y", "z", "1", "2", "3"]


def test_if_condition_bindings_stay_visible():
    src = "p(4).\n!g.\n+!g <- if (p(X)) { .print(in, X) }; .print(out, X).\n"
    assert run_asl(src) == ["in4", "out4"]


def test_fork_join_and_waits_for_both_and_interleaves():
    src = """!m.
+!m <- !a(3) |&| !b(2); .print(both).
+!a(0).
+!a(N) <- .print(a,N); !a(N-1).
+!b(0).
+!b(N) <- .print(b,N); !b(N-1).
"""
    assert run_asl(src) == ["a3", "b2", "a2", "b1", "a1", "both"]


def test_fork_join_xor_continues_after_first_and_drops_other():
    src = """!m.
+!m <- !c ||| !d; .print(one).
+!c <- .print(c1); .print(c2); .print(c3).
+!d <- .print(d1).
"""
    assert run_asl(src) == ["c1", "d1", "one"]


def test_fork_join_groups_in_parentheses():
    """Jason's ``(plan body)`` as a fork operand (demos/concurrent-goals): ``|&|`` binds tighter than
    ``|||``, parentheses group, and a parenthesised sequence runs in order."""
    src = """!m.
+!m <- !c(3) |&| (!a(5) ||| !b(1)); .print(joined); (.print(s1); .print(s2)); (X = 1); .print(X).
+!a(0).
+!a(N) <- .print(a,N); !a(N-1).
+!b(0).
+!b(N) <- .print(b,N); !b(N-1).
+!c(0).
+!c(N) <- .print(c,N); !c(N-1).
"""
    assert run_asl(src) == ["c3", "a5", "b1", "c2", "a4", "c1", "joined", "s1", "s2", "1"]


def test_a_body_in_parentheses_is_no_term():
    """Jason reads ``( body )`` only where a body formula stands: as a term it is a syntax error."""
    import pytest

    from agentspeak.errors import AslSyntaxError
    from agentspeak.parser import parse_program
    for src in ("+!g <- X = (!a ||| !b).", "+!g <- .print((a; b)).", "p :- (a |&| b)."):
        with pytest.raises(AslSyntaxError, match="body in parentheses"):
            parse_program(src, "t.asl")


def test_plan_terms_add_and_remove():
    src = """!m.
+!m <- +{ @dl +!dyn(X) <- .print(dyn, X) }; !dyn(1);
   -{ @dl +!dyn(X) <- .print(dyn, X) }; .relevant_plans({+!dyn(_)}, P); .print(P);
   .add_plan({ @d2 +!dyn(X) <- .print(dyn2, X) }); !dyn(2); .remove_plan(d2);
   .relevant_plans({+!dyn(_)}, P3); .length(P3, N); .print(N).
"""
    assert run_asl(src) == ["dyn1", "[]", "dyn22", "0"]


def test_environment_action_without_environment_fails_with_action_failed():
    src = "!g.\n+!g <- .print(g1); move(1); .print(g2).\n-!g[error(E)] <- .print(recovered, E).\n"
    assert run_asl(src) == ["g1", "recoveredaction_failed"]


def test_tail_recursion_100000_goals():
    src = "!count(0).\n+!count(N) : N < 100000 <- !count(N+1).\n+!count(N) <- .print(done, N).\n"
    assert run_asl(src, timeout=60) == ["done100000"]


def test_include_directive(tmp_path):
    (tmp_path / "lib.asl").write_text("+!hello <- .print(from_lib).\n")
    main = tmp_path / "main.asl"
    main.write_text('{ include("lib.asl") }\n!hello.\n')
    from agentspeak.parser import parse_program
    from agentspeak.runtime import LocalRuntime
    lines: list[str] = []
    rt = LocalRuntime(printer=lambda n, t: lines.append(t))
    rt.add_agent("ag", program=parse_program(main.read_text(), str(main)))
    rt.run(timeout=5)
    assert lines == ["from_lib"]


def test_a_file_run_alone_after_another_file_included_it_still_gets_its_own_includes(tmp_path):
    # in-process runs in a row (pytest, a notebook, an eval worker): team_robot.asl includes faulty.asl then
    # helper.asl, both including geometry.asl, so helper.asl's inclusion skips it; the parse cache kept that
    # helper.asl without geometry.asl, and a later run of helper.asl alone had no geometry rules (undiagnosed)
    (tmp_path / "lib.asl").write_text("double(X, Y) :- Y = X * 2.\n")
    (tmp_path / "first.asl").write_text('{ include("lib.asl") }\n')
    (tmp_path / "second.asl").write_text('{ include("lib.asl") }\n!go.\n+!go : double(2, Y) <- .print(Y).\n'
                                         '+!go <- .print(no_lib).\n')
    (tmp_path / "team.asl").write_text('{ include("first.asl") }\n{ include("second.asl") }\n')
    from agentspeak.parser import parse_program
    from agentspeak.runtime import LocalRuntime

    def run(name: str) -> list[str]:
        lines: list[str] = []
        rt = LocalRuntime(printer=lambda n, t: lines.append(t))
        path = tmp_path / name
        rt.add_agent("ag", program=parse_program(path.read_text(), str(path)))
        rt.run(timeout=5)
        return lines

    assert run("team.asl") == ["4"]
    assert run("second.asl") == ["4"]


def test_a_subgoal_binds_the_callers_variables_when_an_argument_has_annotations():
    # Regression: the finished subgoal was unified back through the plan's own trigger, which had
    # lost the annotations of the event's arguments, so the caller's S = val(3)[source(b)] did not
    # match and X stayed unbound (Jason unifies with the event's literal).
    src = """!start.
+!start <- S = val(3)[source(b)]; !p(S, X); .print(X); !p(val(4)[a, b], Y); .print(Y).
+!p(val(V), A) <- A = V * 10.
"""
    assert run_asl(src) == ["30", "40"]
