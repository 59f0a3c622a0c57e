"""Belief base semantics: sources, annotation merge, -b with sources, rule annotations, percept-free BB."""
from __future__ import annotations

from tests.agentspeak.harness import run_asl


def test_annotations_merge_and_sources_removed_one_by_one():
    src = """!g.
+!g <- +b[x]; +b[y]; ?b[x,y]; .print(merged);
   +c[source(other)]; +c; -c; ?c[source(S)]; .print(S);
   -c[source(other)]; .count(c, N); .print(N).
"""
    assert run_asl(src) == ["merged", "other", "0"]


def test_query_annotations_must_be_subset_of_belief_annotations():
    src = "b[a].\n!g.\n+!g <- ?b[a,c].\n-!g[error(E)] <- .print(E).\n"
    assert run_asl(src) == ["test_goal_failed"]


def test_plan_trigger_annotations_are_the_left_side():
    src = """!g[a,b]. !h.
+!g[a] <- .print(g_with_a).
+!h[a] <- .print(never).
+!h <- .print(h_plain).
"""
    assert run_asl(src) == ["g_with_a", "h_plain"]


def test_deletion_event_and_initial_belief_source():
    src = "b(1).\n!g.\n+!g <- -b(1).\n-b(X)[source(S)] <- .print(deleted, X, S).\n"
    assert run_asl(src) == ["deleted1self"]


def test_update_removes_first_matching_only():
    src = "p(1,a). p(2,b).\n!g.\n+!g <- -+p(3,c); .findall(X, p(X,_), L); .print(L).\n"
    assert run_asl(src) == ["[3,2]"]


def test_count_agrees_with_the_search_for_every_shape_of_query():
    # `.count(b(_, _), N)` counts the b/2 beliefs without a search (stdlib/beliefs._every_belief_of_key):
    # the queries that need the search (repeated or bound variables, annotations, rules) still get it, and
    # every count is the number of solutions .findall finds
    queries = ["b(_, _)", "b(Y, Y)", "b(1, _)", "b(_, _)[x]", "b(_, _)[source(self)]", "~b(_, _)", "b(Z, _)",
               "c(_)", "d(_, _)", "e(_)", "b(_, free)", "b(_)"]
    body = "; ".join(f".count({q}, N{i}); .findall(x, {q}, L{i}); .length(L{i}, M{i}); .print(N{i}, \" \", M{i})"
                     for i, q in enumerate(queries))
    src = f"""b(1, 2). b(1, 3)[x]. b(2, 2). ~b(5, 5). c(1). d(0, 0).
d(K, L) :- b(K, L).
!g.
+!g <- +b(_, free); Z = 2; {body}.
"""
    lines = run_asl(src)
    assert len(lines) == len(queries)
    assert [tuple(line.split()) for line in lines] == [(m, m) for _, m in (line.split() for line in lines)]
    assert [line.split()[0] for line in lines] == ["4", "2", "2", "1", "4", "1", "1", "1", "5", "0", "1", "0"]
    # a belief with an argument of another name space, which no variable without one binds: searched
    src = src.replace("c(1).", "c(1). c(x::a). b(x::a, 1).")
    lines = run_asl(src)
    assert [tuple(line.split()) for line in lines] == [(m, m) for _, m in (line.split() for line in lines)]
    assert [line.split()[0] for line in lines] == ["4", "2", "2", "1", "4", "1", "1", "1", "5", "0", "1", "0"]


def test_beliefs_that_come_and_go_with_ever_new_first_arguments_leave_nothing_behind():
    """Issue 22's soak: a robot's percepts (odometry, a time) are added and removed with a new first argument
    every cycle; the first-argument index kept an empty entry per value ever seen, and agents grew for hours."""
    import gc
    import tracemalloc

    from agentspeak.beliefs import BeliefBase
    from agentspeak.terms import Literal

    percept = (Literal("percept"),)
    bb = BeliefBase()

    def come_and_go(start: int, count: int) -> None:
        for i in range(start, start + count):
            belief = Literal("odom", (i * 0.001, 2.0, 3.0), (Literal("source", percept),))
            bb.add(belief)
            assert bb.candidates(Literal("odom", (i * 0.001, 2.0, 3.0)), {}) == [belief]
            bb.remove(belief)

    come_and_go(0, 200)
    gc.collect()
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        come_and_go(200, 5000)
        gc.collect()
        grown = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert len(bb) == 0
    assert grown < 16 * 1024, f"the belief base kept {grown} bytes after 5000 beliefs came and went"
