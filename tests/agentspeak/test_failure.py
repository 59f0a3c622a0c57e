"""Failure handling: -!g plans with error annotations, cascade, unhandled failures, goal control IAs."""
from __future__ import annotations

from tests.agentspeak.harness import run_asl, run_asl_logged


def test_recovery_plan_gets_error_annotations_and_caller_continues():
    src = """!g.
+!g <- .print(start); !h(1); .print(after).
+!h(X) <- .print(h,X); .fail.
-!h(X)[error(E),code(C),code_line(L)] <- .print("recover ",X," ",E," ",C," ",L).
"""
    assert run_asl(src) == ["start", "h1", "recover 1 ia_failed .fail 3", "after"]


def test_failure_cascades_to_the_lowest_goal_with_a_handler():
    src = """!a.
+!a <- !b; .print(never_a).
+!b <- !c; .print(never_b).
+!c <- X = 1; X > 2.
-!a[error(E)] <- .print(handled_a, E).
"""
    assert run_asl(src) == ["handled_aconstraint_failed"]


def test_no_applicable_plan_fails_the_goal():
    src = "!g.\n+!g <- !h(1).\n+!h(X) : X > 5.\n-!g[error(E)] <- .print(E).\n"
    assert run_asl(src) == ["no_applicable"]


def test_no_relevant_plan_fails_the_goal():
    src = "!g.\n+!g <- !nope.\n-!g[error(E)] <- .print(E).\n"
    assert run_asl(src) == ["no_relevant"]


def test_unhandled_failure_drops_intention_with_warning_naming_plan_and_line(caplog):
    src = "!h. !other.\n+!h <- .print(h1); !k.\n+!k <- X = 1; X > 2; .print(never).\n+!other <- .print(o1); .print(o2).\n"
    out, warnings = run_asl_logged(src, caplog)
    assert out == ["h1", "o1", "o2"]
    assert len(warnings) == 1 and "+!k" in warnings[0] and ":3" in warnings[0]


def test_fail_with_annotations():
    src = "!g.\n+!g <- .fail(error(my_err), why(x)).\n-!g[error(E), why(W)] <- .print(E, W).\n"
    assert run_asl(src) == ["my_errx"]


def test_succeed_goal_finishes_the_goal_and_caller_continues():
    src = """!main.
+!main <- !!stop; !long; .print(main_continues).
+!long <- .print(l1); .wait(2000); .print(never).
+!stop <- .succeed_goal(long).
"""
    # Jason: !!stop becomes an intention in the cycle that pushes long's plan; it runs before long's body
    assert run_asl(src) == ["main_continues"]


def test_fail_goal_posts_failure_event():
    src = """!main.
+!main <- !!stop; !long; .print(after_recovery).
+!long <- .print(l1); .wait(2000); .print(never2).
-!long <- .print(long_failed).
+!stop <- .fail_goal(long).
"""
    assert run_asl(src) == ["long_failed", "after_recovery"]


def test_fail_goal_on_bottom_goal_posts_failure_event():
    src = """!long. !stop.
+!long <- .print(l1); .wait(2000); .print(never).
-!long <- .print(long_failed).
+!stop <- .fail_goal(long).
"""
    assert run_asl(src) == ["l1", "long_failed"]


def test_drop_intention_no_failure_event():
    src = """!long. !stop.
+!long <- .print(l1); .wait(2000); .print(never).
-!long <- .print(never_failed).
+!stop <- .drop_intention(long); .print(dropped); .intend(long).
-!stop <- .print(not_intended).
"""
    assert run_asl(src) == ["l1", "dropped", "not_intended"]


def test_suspend_and_resume_current_and_bottom_goal():
    src = """!s. !w.
+!s <- .print(s0); !!r; .suspend; .print(s1).
+!r <- .print(r); .resume(s).
+!w <- .wait(300); .suspend(w2); .print(w_done).   // long enough for s1 first on a loaded machine
"""
    assert run_asl(src) == ["s0", "r", "s1", "w_done"]


def test_suspend_a_goal_of_another_intention_and_resume():
    src = """!a. !ctl.
+!a <- .print(a1); .print(a2); .print(a3).
+!ctl <- .suspend(a); .print(suspended); .desire(a); .print(still_desire); .resume(a).
"""
    assert run_asl(src) == ["a1", "a2", "suspended", "still_desire", "a3"]


def test_drop_desire_and_intend():
    src = """!a. !ctl.
+!a <- .wait(2000); .print(never).
+!ctl <- .intend(a); .print(intends); .drop_desire(a); .print(dropped); .desire(a).
-!ctl <- .print(no_more_desire).
"""
    assert run_asl(src) == ["intends", "dropped", "no_more_desire"]
