"""In-process speech acts: tell, untell, achieve, askOne, askAll, broadcast, .all_names; sources."""
from __future__ import annotations

from tests.agentspeak.harness import run_mas

BOB = """
price(3). item(a). item(b).
+price(X)[source(S)] <- .print(got, X, S).
-price(X)[source(S)] <- .print(lost, X, S).
+!greet(W)[source(S)] <- .print(W, S).
+hello[source(S)] <- .print(hello, S).
"""


def _lines(lines: list[str], who: str) -> list[str]:
    return [line for line in lines if line.startswith(f"[{who}]")]


def test_tell_achieve_untell_broadcast_and_sources():
    alice = """!start.
+!start <- .send(bob, tell, price(10)); .send(bob, achieve, greet(hi)); .send(bob, untell, price(10));
   .broadcast(tell, hello).
"""
    lines = run_mas({"alice": alice, "bob": BOB})
    assert _lines(lines, "bob") == ["[bob] got3self", "[bob] got10alice", "[bob] hialice",
                                    "[bob] lost10alice", "[bob] helloalice"]


def test_ask_one_ask_all_and_no_answer():
    alice = """!start.
+!start <- .send(bob, askOne, item(X), A); item(V) = A; .print(one, V);
   .send(bob, askAll, item(_), L); .length(L, N); .print(all, N);
   .send(bob, askOne, nothing(_), Nn); .print(none, Nn);
   .all_names(Ns); .print(Ns).
"""
    lines = run_mas({"alice": alice, "bob": "item(a). item(b).\n"})
    assert lines == ["[alice] onea", "[alice] all2", "[alice] nonefalse", "[alice] [alice,bob]"]


def test_ask_one_without_answer_variable_adds_the_belief():
    alice = "!start.\n+!start <- .send(bob, askOne, item(_)); .wait({+item(X)}); .print(got, X).\n"
    lines = run_mas({"alice": alice, "bob": "item(a).\n"})
    assert lines == ["[alice] gota"]


def test_ask_one_timeout_gives_timeout_answer():
    alice = "!start.\n+!start <- .send(bob, askOne, q(_), A, 100); .print(A).\n"
    bob = "+?q(_) <- .wait(2000).\n"
    lines = run_mas({"alice": alice, "bob": bob}, timeout=10)
    assert lines == ["[alice] timeout"]


def test_told_belief_has_sender_source_and_untell_removes_only_that_source():
    alice = "!start.\n+!start <- .send(bob, tell, v(1)); .send(bob, untell, v(1)); .send(bob, achieve, show).\n"
    bob = "v(1).\n+!show <- .findall(S, v(1)[source(S)], L); .print(L).\n"
    assert run_mas({"alice": alice, "bob": bob}) == ["[bob] [self]"]


def test_annotated_answer_does_not_unify_as_left_side():
    alice = "!start.\n+!start <- .send(bob, askOne, item(X), A); A = item(V); .print(never).\n-!start[error(E)] <- .print(E).\n"
    assert run_mas({"alice": alice, "bob": "item(a).\n"}) == ["[alice] constraint_failed"]
