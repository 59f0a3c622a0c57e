"""Jason 3.3.2 behaviours that decide what Jason's own unit-test suite counts and when its timed tests
run (``make jason-tests``, issue 21); one test each, written from Jason's sources (cited per test)."""
from __future__ import annotations

import textwrap

import pytest

from tests.agentspeak.harness import run_asl


def asl(text: str) -> str:
    return textwrap.dedent(text)


# -- a body term is "capplied" when stored (asSyntax/PlanBodyImpl.capply -> ArithFunctionTerm.capply) -----
def test_a_body_term_stored_in_a_belief_holds_its_functions_computed():
    # PlanBodyImpl.capply applies capply to each formula, and ArithFunctionTerm.capply computes a
    # function (.count allows unbound arguments): the stored term holds the count of that moment, so an
    # equal one added later is the same belief and posts no +stored event (Agent.addBel / BeliefBase.add)
    out = run_asl(asl("""
        b(1). b(2).
        !start.
        +!start <- +stored({ .print(.count(b(_))) }); +stored({ .print(1+1) }); +b(3);
                   +stored({ .print(.count(b(_)), X) }); .count(stored(_), N); .print(beliefs(N)).
        +stored(S) <- .print(event(S)).
    """))
    assert out == ["event({ .print(2) })", "event({ .print(3,X) })", "beliefs(2)"]


def test_a_body_term_keeps_what_cannot_be_computed_yet():
    # ArithFunctionTerm.capply: a function that does not allow unbound arguments (.length) stays as it is
    # until they are bound; an if's condition is code (it runs when the body runs)
    out = run_asl(asl("""
        !start.
        +!start <- +stored({ X = .length(L) }); +stored({ if (.length([a]) > 0) { .print(y) } });
                   .findall(S, stored(S), Ss); .print(Ss).
    """))
    assert out == ["[{ if ((.length([a]) > 0)) { .print(y) } },{ (X = .length(L)) }]"]


# -- timing on a machine that gives the process little CPU ------------------------------------------------
class _Clock:
    """A stand-in for the ``time`` module of the interpreter: a process that gets the CPU seldom (each
    reasoning cycle of the agent takes ``per_cycle`` seconds of real time)."""

    def __init__(self) -> None:
        self.now = 1000.0
        self.monotonic = self._monotonic  # one callable, as time.monotonic is (the agent's clock is it)

    def _monotonic(self) -> float:
        return self.now


def _agents(monkeypatch, sources: dict[str, str]):
    from agentspeak import agent as agent_module
    from agentspeak import communication as communication_module
    from agentspeak import suspension as suspension_module
    from agentspeak.runtime import LocalRuntime
    from agentspeak.stdlib.registry import CURRENT
    clock = _Clock()
    monkeypatch.setattr(agent_module, "time", clock)
    monkeypatch.setattr(communication_module, "time", clock)
    monkeypatch.setattr(suspension_module, "time", clock)
    lines: list[str] = []
    runtime = LocalRuntime(printer=lambda name, text: lines.append(f"{name}: {text}"))
    agents = {name: runtime.add_agent(name, text) for name, text in sources.items()}

    def cycles(name: str, n: int, per_cycle: float = 0.0, idle: float | None = None) -> None:
        """``n`` cycles of one agent; the next comes ``per_cycle`` s later, or ``idle`` s later if the agent
        has nothing to do (it waits for a timer: the process comes back to it that much later)."""
        ag = agents[name]
        CURRENT.agent = ag
        for _ in range(n):
            ag.cycle()
            clock.now += per_cycle if ag.has_work() or idle is None else idle
    return clock, lines, cycles


def test_a_busy_agent_whose_cycles_are_slow_runs_its_timers_in_order(monkeypatch):
    # Jason runs each agent on a thread of its own: after !!go's .wait(50) starts, !check's few formulas
    # run long before 50 ms pass. A process that gets the CPU every 200 ms must not end the wait first.
    _, lines, cycles = _agents(monkeypatch, {"ag": asl("""
        !start.
        +!start <- !!go; !!check.
        +!go <- .wait(50); +done; .print(waited).
        +!check <- .print(a); .print(b); .print(c); .print(d);
                   if (done) { .print(late) } else { .print(in_time) }.
    """)})
    cycles("ag", 40, per_cycle=0.2)
    assert lines == ["ag: a", "ag: b", "ag: c", "ag: d", "ag: in_time", "ag: waited"]


def test_the_time_a_busy_agent_lost_is_not_taken_from_its_later_waits(monkeypatch):
    # Jason's queueplan pattern: six .wait(50) in a row, each followed by a few formulas, end long before
    # a .wait(500) begun with them. When each formula takes 50 ms of real time (the process gets the CPU
    # seldom), the time lost while busy must not shorten the waits that follow.
    _, lines, cycles = _agents(monkeypatch, {"ag": asl("""
        !start.
        +!start <- !!chain(0); .wait(500); .count(step(_), N); .print(steps(N)).
        +!chain(6).
        +!chain(I) <- .wait(50); +step(I); .print(I); .print(I); !!chain(I+1).
    """)})
    cycles("ag", 2000, per_cycle=0.05, idle=0.001)
    assert lines[-1] == "ag: steps(6)"


def test_the_time_an_idle_agent_waits_for_the_cpu_after_its_deadline_is_not_taken_from_its_later_waits(monkeypatch):
    # The same chain, but the agent is idle during each .wait(50) and the process comes back to it only
    # 90 ms later (it ran other agents, or got no CPU). On a thread of its own the agent would have gone
    # on at each deadline: the .wait(500) begun with the chain must still end after the sixth step.
    _, lines, cycles = _agents(monkeypatch, {"ag": asl("""
        !start.
        +!start <- !!chain(0); .wait(500); .count(step(_), N); .print(steps(N)).
        +!chain(6).
        +!chain(I) <- .wait(50); +step(I); !!chain(I+1).
    """)})
    cycles("ag", 200, per_cycle=0.0005, idle=0.09)
    assert lines == ["ag: steps(6)"]


def test_a_timer_found_late_is_not_delayed_itself_and_later_ones_keep_their_order(monkeypatch):
    # ... and that time never delays the timer found late itself, nor makes a timer end before its time:
    # .at's event (due at 100 ms, found at 140) comes at once, the .wait(110) after it, not earlier than
    # 110 ms, and after the at's plan ran (as on a thread of its own: 10 ms after the at)
    clock, lines, cycles = _agents(monkeypatch, {"ag": asl("""
        !start.
        +!start <- .at("now +100 ms", {+!at}); .wait(110); .print(waited).
        +!at <- .print(at).
    """)})
    when = {}
    for _ in range(40):
        now = clock.now
        cycles("ag", 1, per_cycle=0.0, idle=0.07)
        for line in lines:
            when.setdefault(line, round((now - 1000.0) * 1000))
    assert lines == ["ag: at", "ag: waited"]
    assert when["ag: at"] == 140 and when["ag: waited"] >= 110


def test_an_answer_sent_before_the_askers_timeout_is_taken_though_read_after_it(monkeypatch):
    # .send(R, askOne, C, A, Timeout): Jason's answer arrives as soon as it is sent; here the asker may
    # read its mailbox after the deadline passed. An answer sent in time counts, a late one does not.
    source = {"a": asl("""
        !start.
        +!start <- .send(b, askOne, v(X), A, 200); .print(A).
    """), "b": "v(1).\n"}
    for answered_after, expected in ((0.1, "a: v(1)[source(b)]"), (0.3, "a: timeout")):
        clock, lines, cycles = _agents(monkeypatch, source)
        cycles("a", 3)
        clock.now += answered_after
        cycles("b", 5)
        clock.now += 10.0  # the asker gets the CPU again long after its deadline
        cycles("a", 5)
        assert lines == [expected]


@pytest.mark.parametrize("queued, late, timeout, expected", [
    (0.0, 0.25, 200, "a: v(1)[source(b)]"),  # the mock's wait ended 250 ms late: not the mock's doing
    (0.05, 0.25, 200, "a: v(1)[source(b)]"),  # ... after it read the ask 50 ms after it was sent
    (0.15, 0.0, 200, "a: timeout"),          # it read the ask 150 ms late: wall time, as Jason's timeout
    (0.0, 0.25, 50, "a: timeout"),           # a wait of 100 ms is too long for 50 ms
])
def test_an_answer_counts_as_sent_when_the_answerer_would_have_sent_it_on_a_thread_of_its_own(
        monkeypatch, queued, late, timeout, expected):
    # Jason's suite, send.asl test_timeout_send: the mock answers through a +? plan that waits 100 ms; the
    # asker gives it 200 ms, then 50 ms. The process reaches the mock `queued` s after the ask was sent, and
    # comes back to it `late` s after its wait's deadline (it ran other agents, or got no CPU), which the
    # mock's own timers count as lost time (lag): on a thread of its own it would have gone on at the
    # deadline. So does its answer. The asker itself gets the CPU again long after its deadline.
    clock, lines, cycles = _agents(monkeypatch, {"a": asl(f"""
        !start.
        +!start <- .send(b, askOne, v(X), A, {timeout}); .print(A).
    """), "b": asl("""
        +?v(X) <- .wait(100); X = 1.
    """)})
    cycles("a", 3)
    clock.now += queued
    cycles("b", 6)  # reads the ask, starts the wait
    assert lines == []
    clock.now += 0.1 + late
    cycles("b", 6)  # the wait ends, the answer goes
    clock.now += 10.0
    cycles("a", 5)
    assert lines == [expected]


def test_the_receiver_of_an_ask_with_a_timeout_goes_before_agents_woken_earlier():
    # Jason runs the asked agent on a thread of its own: it reads the ask at once. Here the agents of a run
    # take turns; one woken by an ask with a timeout (or by an answer to an ask) goes first, as an agent whose
    # timer is due does, but at most URGENT_IN_ROW in a row before an agent woken earlier, so none starves
    import threading

    from agentspeak.communication import Message, stamp_sent
    from agentspeak.runtime import URGENT_IN_ROW, LocalRuntime
    from agentspeak.terms import Literal
    runtime = LocalRuntime()
    names = ["c", "b", "d", "e", "f"]
    for name in names:
        runtime.add_agent(name, "")
    runtime.ready.clear()
    runtime.busy.clear()
    runtime._ready_set.clear()
    runtime._loop_thread = threading.get_ident()  # delivered from the loop's own thread, as agents send

    def send(to: str, performative: str, deadline: bool) -> None:
        msg = Message("a", to, performative, Literal("v", (1,)))
        if deadline:
            stamp_sent(msg)
        runtime.route(msg)

    send("c", "tell", False)
    send("b", "askOne", True)
    assert [ag.name for ag in runtime.ready] == ["b", "c"]
    assert URGENT_IN_ROW == 3
    send("d", "askOne", True)
    send("e", "askOne", True)
    send("f", "askOne", True)  # a fourth in a row waits behind c
    assert [ag.name for ag in runtime.ready] == ["e", "d", "b", "c", "f"]


# -- .drop_all_intentions (stdlib/drop_all_intentions.java; Jason's suite: stdlib/drop_all_intentions.asl) --
def test_drop_all_intentions_keeps_the_calling_intention():
    # Circumstance.clearRunningIntentions empties I, and the intention running the formula is not in I
    # (Agent.selectIntention polls it; TransitionSystem requeues it after the formula): "all intentions
    # except the one where .drop_all_intentions appears are dropped". Jason's suite asserts after it.
    out = run_asl(asl("""
        !start.
        +!start <- !!g(1); !!g(2); .wait(20);
                   .drop_all_intentions;
                   .findall(T, .intention(_, _, [im(_, {+!T[_]}, _, _)]), L); .print(L); .print(after).
        +!g(X) <- .wait(300); .print(never(X)).
    """), timeout=2.0)
    assert out == ["[start]", "after"]


def test_drop_all_intentions_cancels_the_events_at_would_post():
    # at.cancelAts (called by drop_all_intentions and so by drop_all_desires); a !!goal's event stays: it
    # belongs to no intention (Event.isInternal is false), as the environment's and messages' events
    out = run_asl(asl("""
        !start.
        +!start <- .at("now +100 ms", {+!late}); .drop_all_intentions; !!next; .wait(300); .print(done).
        +!late <- .print(late).
        +!next <- .print(next).
    """), timeout=2.0)
    assert out == ["next", "done"]
