"""What the interpreter's speed-ups must not change: agents of one source share parsed terms but not
plans or variables, messages from other threads still wake the scheduler, tail calls return results."""
from __future__ import annotations

import threading
import time

from agentspeak.communication import Message
from agentspeak.parser import parse_program
from agentspeak.runtime import LocalRuntime
from agentspeak.terms import Literal

from tests.agentspeak.harness import run_asl, run_mas

SOURCE = """
p(1).
+!g(X) : p(X) <- .print(X).
"""


def test_a_source_parsed_twice_gives_programs_of_their_own():
    first = parse_program(SOURCE, "shared.asl")
    second = parse_program(SOURCE, "shared.asl")
    assert first is not second and first.plans[0] is not second.plans[0]
    assert first.plans[0].trigger is second.plans[0].trigger  # immutable terms are shared
    first.plans.clear()
    first.beliefs.clear()
    third = parse_program(SOURCE, "shared.asl")
    assert len(third.plans) == 1 and len(third.beliefs) == 1


def test_agents_of_one_source_get_their_own_plan_labels():
    rt = LocalRuntime(printer=lambda name, text: None)
    a = rt.add_agent("a", SOURCE)
    b = rt.add_agent("b", SOURCE)
    assert a.plans.plans[0].label != b.plans.plans[0].label


def test_a_senders_free_variable_is_not_the_receivers_even_in_the_same_plan():
    # a sends p(C) with C free; b runs the same clause and binds its own C: A must stay free
    src = """
    !go.
    +!go : .my_name(a) <- !p(start).
    +!go.
    +!p(A) <- if (.my_name(a)) { .send(b, achieve, p(C)) } else { C = 5; if (A == 5) { .print("captured") } else { .print("apart") } }.
    """
    assert run_mas({"a": src, "b": src}) == ["[b] apart"]


def test_a_message_from_another_thread_wakes_an_idle_runtime():
    src = "+!hello(N) <- .print(hello, N); .stopMAS."
    lines: list[str] = []
    rt = LocalRuntime(printer=lambda name, text: lines.append(text))
    rt.add_agent("ag", src)

    def later() -> None:
        while rt._loop_thread is None:   # wait for the loop, then for it to sleep (nothing to do)
            time.sleep(0.01)
        while not rt._sleepers:
            time.sleep(0.01)
        rt.route(Message("outsider", "ag", "achieve", Literal("hello", (7,))))

    t = threading.Thread(target=later)
    t.start()
    why = rt.run(timeout=10, stop_when_idle=False)
    t.join()
    assert why == "stopped" and lines == ["hello7"]


def test_tail_calls_give_their_result_to_the_caller_and_keep_the_stack_flat():
    src = """
    !start.
    +!start <- !f(3, R); .print(R); !g(0, S); .print(S).
    +!f(N, R) : N > 0 <- .intend(f(_, _)); !f(N - 1, R).
    +!f(0, done(X)) <- X = 7.
    +!g(N, S) : N < 3 <- .print(N); !g(N + 1, S).
    +!g(N, N).
    """
    assert run_asl(src) == ["done(7)", "0", "1", "2", "3"]


def test_context_lookups_backtrack_over_beliefs_and_leave_no_bindings_behind():
    src = """
    n(1). n(2). n(3). m(7)[source(percept)].
    !go.
    +!go : n(X) & X > 1 & not n(5) <- .print(X); !h; !k; !w.
    +!h : n(Y) & Y > 5 <- .print(never).
    +!h : m(Z) <- .print(Z).
    +!k : n(4) | n(V) <- .print(V).
    +!w : .findall(X, n(X) & X >= 2, L) <- .print(L).
    """
    assert run_asl(src) == ["2", "7", "1", "[2,3]"]
