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
