"""The per-message path (send -> mailbox -> event -> intention) keeps Jason's semantics on its fast paths:
contents of every shape, sources, plan selection after failing contexts, ``+!kqml_received`` overrides."""
from __future__ import annotations

from tests.agentspeak.harness import run_asl_logged, run_mas

RELAY = """
+!t(H, X)[source(S)] : limit(M) & H >= M <- .print(done, H, " ", X, " ", S).
+!t(H, X)[source(S)] : next(N) <- H1 = H + 1; .send(N, achieve, t(H1, X)).
"""


def test_a_ring_passes_contents_of_every_shape_with_the_senders_source():
    starter = "!go.\n+!go <- .send(a, achieve, t(0, {0})).\n"
    contents = ['"text"', "2.5", "atom", "f(g(1), [1, 2])", "p[q]", "_"]
    for content in contents:
        agents = {"s": starter.replace("{0}", content),
                  "a": "next(b). limit(3).\n" + RELAY, "b": "next(a). limit(3).\n" + RELAY}
        lines = run_mas(agents)
        assert len(lines) == 1 and lines[0].startswith("[b] done3 "), (content, lines)
        assert lines[0].endswith(" a"), (content, lines)
    shown = {c: run_mas({"s": starter.replace("{0}", c), "a": "next(b). limit(1).\n" + RELAY,
                         "b": "next(a). limit(1).\n" + RELAY})[0] for c in contents[:5]}
    assert shown == {'"text"': "[b] done1 text a", "2.5": "[b] done1 2.5 a", "atom": "[b] done1 atom a",
                     "f(g(1), [1, 2])": "[b] done1 f(g(1),[1,2]) a", "p[q]": "[b] done1 p[q] a"}


def test_an_achieve_from_oneself_has_source_self_and_a_variable_content_is_renamed_apart(caplog):
    src = """!go.
+!go <- .my_name(Me); .send(Me, achieve, g(1, X)); X = 5; .print(sent, X).
+!g(N, Y)[source(S)] <- .print(got, N, S); Y = 7; .print(y, Y).
"""
    out, warnings = run_asl_logged(src, caplog)
    # round robin: the sender's next step runs before the receiver's new intention; the receiver's
    # Y is its own (binding it does not bind the sender's X, already 5)
    assert out == ["got1self", "sent5", "y7"] and warnings == []


def test_integer_sums_in_a_constraint_keep_jason_numbers_and_unify_when_bound(caplog):
    src = """!go.
+!go <- A = 9007199254740991; B = A + 1; .print(B); C = 2; C = 1 + 1; .print(ok);
   D = 3; E = D * 4 - 1; .print(E).
+!bad <- C = 2; C = 1 + 2; .print(never).
-!bad[error(E)] <- .print(failed, E).
!bad.
"""
    out, _ = run_asl_logged(src, caplog)
    assert sorted(out) == sorted(["9007199254740992", "ok", "11", "failedconstraint_failed"])


def test_the_next_plan_sees_none_of_the_bindings_of_a_failed_or_broken_context(caplog):
    src = """lim(5). v(1).
!go(7). !go(2). !go(0).
+!go(7) : v(M) & M > 5 <- .print(never).
+!go(H) : lim(M) & H >= M <- .print(big, H, M).
+!go(H) : v(Z) & Z = H + 1 & H < 1 & .no_such_action(Z) <- .print(never).
+!go(H) : v(M) <- .print(small, H, M).
"""
    out, warnings = run_asl_logged(src, caplog)
    assert out == ["big75", "small21", "small01"]
    assert len(warnings) == 1 and "error in the context" in warnings[0]  # the unknown action, for !go(0)


def test_kqml_received_plans_override_a_performative_even_when_added_later():
    receiver = """
+!arm <- +{+!kqml_received(S, achieve, C, M) <- .print(custom, S, C)}.
+!g(X)[source(S)] <- .print(plain, X, S); !arm.
"""
    sender = "!go.\n+!go <- .send(r, achieve, g(1)); .wait(50); .send(r, achieve, g(2)).\n"
    assert run_mas({"s": sender, "r": receiver}) == ["[r] plain1s", "[r] customsg(2)"]



def _slots(obj) -> dict:
    """Every slot of ``obj`` by name: an AttributeError names a slot that a fast path left unset."""
    names = [n for cls in type(obj).__mro__ for n in getattr(cls, "__slots__", ()) if n != "__weakref__"]
    return {n: getattr(obj, n) for n in names}


def test_objects_the_message_path_builds_without_their_class_call_are_complete():
    # receive_message, Agent.deliberate, .send and internal actions build Literal, Trigger, Event,
    # Intention, IntendedMeans, Frame, Message and IAContext with object.__new__: compare every slot
    # with what the constructors make
    from agentspeak.agent import Agent, IAContext
    from agentspeak.arch import AgentArch
    from agentspeak.communication import Message, receive_message
    from agentspeak.intentions import Event, IntendedMeans, Intention
    from agentspeak.parser import parse_program
    from agentspeak.program import ACHIEVE, ADD, Trigger
    from agentspeak.stdlib.registry import STDLIB, Registry
    from agentspeak.terms import Literal

    sent: list = []
    seen: list = []

    class Recorder(AgentArch):
        def send(self, agent, message):
            sent.append(message)

    lib = Registry(dict(STDLIB.actions))
    lib.register(".see", lambda ctx, *args: seen.append(ctx), 0, None)
    agent = Agent("r", arch=Recorder(), registry=lib)
    agent.load(parse_program("+!g(X)[source(S)] <- .see(X); .send(S, achieve, h(X, 2)).\n"))
    receive_message(agent, Message("s", "r", "achieve", Literal("g", (7,))))
    event = agent.events[-1]
    source = Literal("source", (Literal("s"),))
    expected = Event(Trigger(ADD, ACHIEVE, Literal("g", (7,), (source,))))
    assert _slots(event)["intention"] is None and _slots(event)["handles"] is None
    assert _slots(event.trigger) == _slots(expected.trigger)
    assert _slots(event.trigger.literal) == _slots(expected.trigger.literal)

    agent.deliberate()
    intention = agent.running[-1]
    im = intention.stack[0]
    made = Intention(IntendedMeans(im.plan, im.b, im.event_literal))
    assert {k: v for k, v in _slots(intention).items() if k not in ("id", "stack")} == \
        {k: v for k, v in _slots(made).items() if k not in ("id", "stack")}
    assert intention.id < made.id and len(intention.stack) == 1
    assert {k: v for k, v in _slots(im).items() if k != "frames"} == \
        {k: v for k, v in _slots(made.stack[0]).items() if k != "frames"}
    assert [_slots(f) for f in im.frames] == [_slots(f) for f in made.stack[0].frames]

    agent.act()  # .see(X)
    agent.act()  # .send(S, achieve, h(X, 2))
    assert not agent.running and intention.dropped
    ctx = seen[0]
    assert _slots(ctx) == _slots(IAContext(agent, intention, im, im.b, ctx.trail))
    message = sent[0]
    assert _slots(message) == _slots(Message("r", "s", "achieve", Literal("h", (7, 2))))
    assert _slots(message.content) == _slots(Literal("h", (7, 2)))


def test_a_tell_does_not_overtake_an_earlier_untell_of_the_same_sender_still_in_the_event_queue():
    """Issue 21: a mock untells ``sleeping(tom)`` then tells it again; both wait in the mailbox while other
    events are queued, so the untell (an event, Jason's kqmlPlans) is handled after the tell was read.
    Applied at once, the tell was overtaken and the belief lost: the tester's ``.wait(sleeping(tom))``
    hung. The sender's order is kept: the last message, the tell, decides. Timing by hand: no load."""
    from agentspeak.communication import Message
    from agentspeak.runtime import LocalRuntime
    from agentspeak.terms import Literal, to_str

    def beliefs_after(*performatives: str) -> list[str]:
        runtime = LocalRuntime(printer=lambda name, text: None)
        runtime.add_agent("a", "sleeping(tom)[source(tom)].\n!g1. !g2.\n+!g1 <- true.\n+!g2 <- true.\n")
        agent = runtime.agents["a"]
        fact = Literal("sleeping", (Literal("tom"),))
        agent.mailbox.extend(Message("tom", "a", perf, fact) for perf in performatives)
        runtime.run(timeout=5.0)
        return [to_str(b) for b in agent.bb.literals()]

    assert beliefs_after("untell", "tell") == ["sleeping(tom)[source(tom)]"]
    assert beliefs_after("tell", "untell") == []


def test_a_belief_added_by_a_plan_is_built_complete():
    # `+b(...)` with arguments bound to numbers, strings and atoms builds its belief without resolve
    # (body._belief_literal): every slot as Literal's constructor makes it, with source(self)
    from agentspeak.agent import Agent
    from agentspeak.beliefs import SOURCE_SELF
    from agentspeak.parser import parse_program
    from agentspeak.terms import Literal

    agent = Agent("r")
    agent.load(parse_program('!g(3).\n+!g(X) <- Y = a; +b(X, Y, "s", 1.5, c); +~n; +f(g(X)).\n'))
    for _ in range(8):
        agent.cycle()
    expected = {"b": Literal("b", (3, Literal("a"), "s", 1.5, Literal("c")), (SOURCE_SELF,)),
                "n": Literal("n", (), (SOURCE_SELF,), True),
                "f": Literal("f", (Literal("g", (3,)),), (SOURCE_SELF,))}
    stored = {lit.functor: lit for lit in agent.bb.literals()}
    assert {name: _slots(lit) for name, lit in stored.items()} == {name: _slots(lit) for name, lit in expected.items()}
