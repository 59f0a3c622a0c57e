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
    # untell is no fast path in Jason: it becomes +!kqml_received(alice, untell, ...), whose plan posts
    # the -price event only when that event is selected, a cycle after `tell hello` was read
    assert _lines(lines, "bob") == ["[bob] got3self", "[bob] got10alice", "[bob] hialice",
                                    "[bob] helloalice", "[bob] lost10alice"]


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


def test_an_ask_is_answered_after_the_goal_sent_before_it():
    """Jason handles askOne as the event +!kqml_received(...) when it is selected, not when the message
    is read: a plan for it added by a goal achieved just before (the same sender's previous message)
    answers it (Jason's own test_kqml_simple_send)."""
    maria = """
        ready.            // its event comes first: maria's events lag one cycle behind her messages
        +ready <- true.
        +!gg <- .add_plan({+!kqml_received(S, askOne, fullname, M) <- .send(S, tell, name("Maria"), M)}, kk, begin).
    """
    bob = """!s.
        +!s <- .send(maria, achieve, gg); .send(maria, askOne, fullname, X); .print(X).
    """
    lines = run_mas({"bob": bob, "maria": maria})  # bob first: both messages wait when maria starts
    assert lines == ['[bob] name("Maria")[source(maria)]']


def test_asks_no_longer_awaited_leave_nothing_behind():
    """Issue 22's soak: an ask that timed out, or whose intention was dropped (a new task drops every
    intention), kept its entry in the asker's pending answers (callback, future, lock) for as long as the
    agent ran (bob never answers, as a helper that dropped the question for a new task). After 20 of each,
    nothing is pending."""
    from agentspeak.runtime import LocalRuntime

    alice = """!start.
+!start <- for ( .range(I, 1, 20) ) { .send(bob, askOne, q(I), A, 10) };
   for ( .range(I, 1, 20) ) { !!ask(I) };
   .wait(300); .drop_intention(ask(_)); .print(done).
+!ask(I) <- .send(bob, askOne, q(I), A); .print(never, A).
"""
    bob = "+?q(_) <- .wait({+never}).\n"
    lines: list[str] = []
    runtime = LocalRuntime(printer=lambda name, text: lines.append(f"[{name}] {text}"))
    runtime.add_agent("alice", alice)
    runtime.add_agent("bob", bob)
    runtime.run(timeout=2.0)
    assert lines == ["[alice] done"]
    assert runtime.agents["alice"].pending_asks == {}
