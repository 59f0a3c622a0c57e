"""Speech acts with Jason's semantics (KQML performatives), independent of the transport.

A ``Message`` carries a performative and content (a term). ``receive_message`` is what the
receiving agent does with it, one message per reasoning cycle, as Jason's default ``kqmlPlans.asl``
(written here in Python). As in Jason, tell, achieve and signal take effect when the message is read
and every other performative when its event ``+!kqml_received(...)`` is selected. A program can override the semantics
of any performative, or add new ones, with plans for ``+!kqml_received(Sender, Performative,
Content, MsgId)``: when such a plan is relevant, the message becomes that goal instead.
"""
from __future__ import annotations

import itertools
import logging
import os
import time
from typing import Any

from agentspeak.beliefs import SELF, SOURCE_SELF, source
from agentspeak.intentions import Event
from agentspeak.program import ACHIEVE, ADD, BEL, DEL, Plan, PlanTerm, Trigger
from agentspeak.solver import SolveError, solve
from agentspeak.terms import NIL, Cons, Literal, Term, Var, is_ground, list_items, make_list, rename, resolve, to_str
from agentspeak.terms import ns_atom as _atom_of   # a sender's atom: one object per name, the table bounded

log = logging.getLogger("faultmas.agentspeak")

PERFORMATIVES = ("tell", "untell", "achieve", "unachieve", "askOne", "askAll", "tellHow",
                 "untellHow", "askHow", "signal")

_ids = itertools.count(1)
_prefix = f"{os.getpid():x}{os.urandom(3).hex()}"   # not uuid: its import (platform) costs start-up


def new_message_id() -> str:
    """Unique across processes (pid + random prefix + counter)."""
    return f"mid{_prefix}{next(_ids)}"


class Message:
    """A speech act. Its ``msg_id`` (unique across processes) is made when first read: most messages
    (``tell``, ``achieve``) never need one, and making it is a good part of an in-process send.
    ``.send`` builds messages without ``__init__`` (see ``agentspeak.agent._new``)."""

    __slots__ = ("sender", "receiver", "performative", "content", "_msg_id", "in_reply_to", "sent_at", "read_at")

    def __init__(self, sender: str, receiver: str, performative: str, content: Term,
                 msg_id: str | None = None, in_reply_to: str | None = None) -> None:
        self.sender = sender
        self.receiver = receiver
        self.performative = performative
        self.content = content
        self._msg_id = msg_id
        self.in_reply_to = in_reply_to
        self.sent_at = None  # monotonic time an ask with a timeout, or a reply to an ask, was sent (in this process)
        self.read_at = None  # an ask: when it was read, see _answer

    @property
    def msg_id(self) -> str:
        mid = self._msg_id
        if mid is None:
            mid = self._msg_id = new_message_id()
        return mid

    @msg_id.setter
    def msg_id(self, value: str) -> None:
        self._msg_id = value

    def __eq__(self, other: object) -> bool:
        return (type(other) is Message and self.sender == other.sender and self.receiver == other.receiver
                and self.performative == other.performative and self.content == other.content
                and self.msg_id == other.msg_id and self.in_reply_to == other.in_reply_to)

    __hash__ = None  # type: ignore[assignment]  # mutable, like the dataclass it replaces

    def __repr__(self) -> str:
        return (f"Message(sender={self.sender!r}, receiver={self.receiver!r}, performative={self.performative!r}, "
                f"content={self.content!r}, msg_id={self.msg_id!r}, in_reply_to={self.in_reply_to!r})")

    def __str__(self) -> str:
        return f"<{self.msg_id},{self.sender},{self.performative},{self.receiver},{to_str(self.content)}>"


def _items(content: Term) -> list:
    if isinstance(content, Cons) or content is NIL:
        try:
            return list_items(content)
        except TypeError:
            return [content]
    return [content]


def _strip_self_source(lit: Literal) -> Literal:
    if not lit.annots:
        return lit
    kept = tuple(a for a in lit.annots if a != SOURCE_SELF)
    return Literal(lit.functor, lit.args, kept or None, lit.neg)


_SOURCES: dict[str, Literal] = {}
_new = object.__new__  # objects of the message path without class calls: see agentspeak.agent._new
_SELF_ANNOTS = (SOURCE_SELF,)


def _source_of(who: Term) -> Literal:
    """``source(who)``, made once per sender name (hostile senders cannot grow the table much)."""
    if type(who) is not Literal or who.args:
        return source(who)
    found = _SOURCES.get(who.functor)
    if found is None:
        found = source(who)
        if len(_SOURCES) < 10_000:
            _SOURCES[who.functor] = found
    return found


def _annotate(lit: Term, who: Term) -> Term:
    """``lit[source(who)]``, its variables renamed apart (Jason's ``!!CA`` does so): agents of one
    source share their plans' variables, and a sender's variable must not be the receiver's."""
    if isinstance(lit, Literal):
        if not is_ground(lit):
            lit = rename(lit, {})
        if lit.annots is None:  # the usual content: no annotations of its own
            return Literal(lit.functor, lit.args, (_source_of(who),), lit.neg)
        return nested_source(lit, who)
    return lit


def nested_source(lit: Literal, who: Term) -> Literal:
    """Jason's ``.add_nested_source``: ``p[a,b]`` from ``who`` is ``p[source(who)[a,b]]`` (what a told
    belief or an answer was annotated with stays visible, inside the source)."""
    annots = lit.annots
    src = Literal("source", (who,), annots if annots else None)
    return Literal(lit.functor, lit.args, (src,), lit.neg)


_SOURCE_ANNOTS: dict[str, tuple] = {}


def _source_annots(name: str) -> tuple:
    """``(source(name),)``: the annotations of a plain message content, made once per sender name."""
    found = _SOURCE_ANNOTS.get(name)
    if found is None:
        found = (_source_of(_atom_of(name)),)
        if len(_SOURCE_ANNOTS) < 10_000:
            _SOURCE_ANNOTS[name] = found
    return found


def _untell_waits(agent: Any, msg: Message) -> bool:
    """Does an earlier untell of the same sender, of a belief this tell is about (same functor and arity),
    still wait in the event queue as ``+!kqml_received``? Applied at once, the tell would be overtaken
    by it and the belief lost: a mock's untell of ``sleeping(M)`` then its tell of it left the tester
    believing ``not sleeping(M)``, and its ``.wait(sleeping(M))`` waited for ever (issue 21). A Jason
    agent on a thread of its own reads such messages far apart; here both can be in the mailbox. The
    tell then takes the event route too (Jason's semantics without its fast path, as in its sync mode):
    the sender's last word on a belief stands. Tells of other beliefs keep the fast path (and Jason's
    order of the events that follows from it)."""
    held = agent.__dict__.get("kqml_messages")
    if not held:
        return False
    told = {(item.functor, len(item.args)) for item in _items(msg.content) if isinstance(item, Literal)}
    for ev in agent.events:
        lit = ev.trigger.literal
        if type(lit) is Literal and lit.functor == "kqml_received" and len(lit.args) == 4:
            earlier = held.get(lit.args[3])
            if earlier is not None and earlier.sender == msg.sender and earlier.performative == "untell" \
                    and any(isinstance(item, Literal) and (item.functor, len(item.args)) in told
                            for item in _items(earlier.content)):
                return True
    return False


def receive_message(agent: Any, msg: Message, by_default: bool = False) -> None:
    """Apply the semantics of one received message (``by_default``: the default semantics, even if
    ``+!kqml_received`` plans are relevant)."""
    perf = msg.performative
    name = msg.sender
    if perf in _ASKS:
        msg.read_at = (time.monotonic(), agent.timer_lost)  # see _answer
    # replies to a pending ask resume the asking intention
    if msg.in_reply_to is not None and msg.in_reply_to in agent.pending_asks:
        agent.pending_asks.pop(msg.in_reply_to)(msg)
        return
    plans = agent.plans  # has +!kqml_received(S, P, C, M) a relevant plan? Known per plan index
    if plans._index is None:
        plans._build()
    # Jason turns a message into the event +!kqml_received(S, P, C, M), handled when the event is
    # selected (by the user's plans, else by kqmlPlans.asl); only tell, achieve and signal take a fast
    # path at once, and only while no user plan for +!kqml_received exists (TransitionSystem.applyProcMsg).
    # An ask is therefore answered after the goals and intentions that came before it had their turn.
    if not by_default and (plans.kqml_override or perf not in _FAST_PATH
                           or (perf == "tell" and _untell_waits(agent, msg))):
        sender = _atom_of(name) if name != agent.name else SELF
        goal = Literal("kqml_received", (sender, Literal(perf), msg.content, msg.msg_id), (SOURCE_SELF,))
        # kept until a plan handles it: when none of the user's +!kqml_received plans applies, the
        # message gets the default semantics (Jason's kqmlPlans.asl comes after the user's plans)
        held = agent.__dict__.setdefault("kqml_messages", {})
        if len(held) >= 1000:
            del held[next(iter(held))]
        held[msg.msg_id] = msg
        agent.post_external(Trigger(ADD, ACHIEVE, goal), force=True)
        return
    content = msg.content
    if perf == "achieve" and type(content) is Literal and content.annots is None and content.annot_tail is None:
        # _achieve of one literal of numbers, strings and atoms (ground: nothing to rename), inlined
        for a in content.args:
            ta = type(a)
            if not (ta is int or ta is float or ta is str or (ta is Literal and not a.args and a.annots is None)):
                break
        else:
            annots = _SOURCE_ANNOTS.get(name) if name != agent.name else _SELF_ANNOTS
            if annots is None:
                annots = _source_annots(name)
            # Event(Trigger(ADD, ACHIEVE, Literal(content.functor, content.args, annots, content.neg)))
            # without class calls
            lit = _new(Literal)
            lit.functor, lit.args, lit.annots = content.functor, content.args, annots
            lit.neg, lit.annot_tail, lit._hash = content.neg, None, None
            trigger = Trigger.__new__(Trigger)
            trigger.op, trigger.kind, trigger.literal = ADD, ACHIEVE, lit
            if agent.event_waiters:
                agent._notify_waiters(trigger)
            ev = Event.__new__(Event)
            ev.trigger, ev.intention, ev.handles = trigger, None, None
            agent.events.append(ev)
            return
    sender = _atom_of(name) if name != agent.name else SELF
    handler = _HANDLERS.get(perf)
    if handler is None:
        log.warning("[%s] message from %s dropped: unknown performative '%s'", agent.name, msg.sender, perf)
        agent.count_dropped("unknown_performative")
        return
    try:
        handler(agent, msg, sender)
    except (SolveError, TypeError, ValueError) as exc:
        log.warning("[%s] message from %s dropped: %s", agent.name, msg.sender, exc)


def receive_by_default(agent: Any, msg: Message) -> None:
    """The default semantics of a message, also when the agent has ``+!kqml_received`` plans (for a
    message none of them applies to)."""
    receive_message(agent, msg, True)


def _tell(agent, msg: Message, sender: Term) -> None:
    for item in _items(msg.content):
        if not isinstance(item, Literal) or not is_ground(item):
            log.warning("[%s] tell from %s ignored: '%s' is not a ground literal", agent.name, msg.sender, to_str(item))
            continue
        added = agent.bb.add(_annotate(item, sender))
        if added is not None:
            agent.post_external(Trigger(ADD, BEL, added))


def _untell(agent, msg: Message, sender: Term) -> None:
    for item in _items(msg.content):
        if not isinstance(item, Literal):
            continue
        b: dict = {}
        for fact in list(agent.bb.candidates(item, b)):
            from agentspeak.unify import unifies
            if unifies(item.without_annots(), fact.without_annots(), {}):
                removed = agent.bb.remove(Literal(fact.functor, fact.args, (source(sender),), fact.neg))
                if removed is not None:
                    agent.post_external(Trigger(DEL, BEL, removed))
                break


def _achieve(agent, msg: Message, sender: Term) -> None:
    for item in _items(msg.content):
        if isinstance(item, Literal):
            agent.post_external(Trigger(ADD, ACHIEVE, _annotate(item, sender)), force=True)


def _unachieve(agent, msg: Message, sender: Term) -> None:
    from agentspeak.stdlib.bdi import drop_desire
    for item in _items(msg.content):
        if isinstance(item, Literal):
            drop_desire(agent, item)


def _signal(agent, msg: Message, sender: Term) -> None:
    for item in _items(msg.content):
        if isinstance(item, Literal):
            agent.post_external(Trigger(ADD, BEL, _annotate(item, sender)), force=False)


def stamp_sent(msg: Message) -> None:
    """An ask with a timeout: when it was sent. Its receiver, and the asker for the answer (stamped by
    _answer), go first in this process's queue of woken agents (LocalRuntime._route_from)."""
    msg.sent_at = time.monotonic()


def _answer(agent, msg: Message, performative: str, content: Term) -> None:
    """Reply to the ask ``msg``. An answer sent before the asker's timeout counts, even if the asker reads
    it later (``.send``); it counts as sent when this agent would have sent it on a thread of its own, that is
    without the time it lost since it read the ask: a ``.wait`` that ended late because the process ran other
    agents or got no CPU, which its own timers do not count either (Agent._count_lag). Its own waits and work
    count in full, and so does the time before it read the ask (wall time, as Jason's timeout)."""
    reply = Message(agent.name, msg.sender, performative, content, in_reply_to=msg.msg_id)
    now = time.monotonic()
    read = getattr(msg, "read_at", None)
    if read is not None and agent.clock == time.monotonic:  # lost time is counted on the wall clock only
        read_at, lost_then = read
        lost = agent.timer_lost - lost_then
        if lost > 0.0:
            now = max(read_at, now - lost)
    reply.sent_at = now
    agent.arch.send(agent, reply)


def _with_annots_of_answer(query: Term) -> Term:
    """The query with an open annotation tail: its answer carries the annotations of the belief that
    answered it (Jason answers ``askOne value(X)`` with ``value(10)[source(bob)]``)."""
    if isinstance(query, Literal) and query.annot_tail is None:
        return Literal(query.functor, query.args, query.annots, query.neg, Var("_Annots"))
    return query


def _ask_one(agent, msg: Message, sender: Term) -> None:
    query = msg.content
    b: dict = {}
    pattern = _with_annots_of_answer(query)
    for _ in solve(agent, pattern, b):
        _answer(agent, msg, "tell", _strip_self_source(resolve(pattern, b)) if isinstance(query, Literal) else resolve(query, b))
        return
    # no belief: try a +?q plan, answering when it finishes
    if isinstance(query, Literal) and agent.plans.relevant(Trigger(ADD, "?", query)):
        _ask_by_plan(agent, msg, query)
        return
    _answer(agent, msg, "untell", query)


def _ask_by_plan(agent, msg: Message, query: Literal) -> None:
    """Run ``?query`` in a new intention (through its +?q plan) and send the answer when it is done."""
    from agentspeak.intentions import IntendedMeans, Intention
    from agentspeak.program import PyCall, Test

    def reply(ctx) -> bool:
        _answer(agent, msg, "tell", _strip_self_source(ctx.resolve(query)))
        return True

    plan = Plan(Trigger(ADD, ACHIEVE, Literal("kqml_ask_answer")), None, (Test(query, 0), PyCall(reply, 0)))
    intention = Intention()
    intention.stack.append(IntendedMeans(plan, {}, plan.trigger.literal))
    agent._requeue(intention)


def _ask_all(agent, msg: Message, sender: Term) -> None:
    query = msg.content
    b: dict = {}
    answers = []
    pattern = _with_annots_of_answer(query)
    for _ in solve(agent, pattern, b):
        value = resolve(pattern, b)
        answers.append(_strip_self_source(value) if isinstance(value, Literal) else value)
    _answer(agent, msg, "tell", make_list(answers))


def _tell_how(agent, msg: Message, sender: Term) -> None:
    if not agent.accepts_plans_from(msg.sender):
        log.warning("[%s] tellHow from %s refused: sender not allowed to send plans", agent.name, msg.sender)
        agent.count_dropped("tellHow_refused")
        return
    from agentspeak.stdlib.plans import add_plan_term
    for item in _items(msg.content):
        add_plan_term(agent, item, sender, at_end=True)


def _untell_how(agent, msg: Message, sender: Term) -> None:
    for item in _items(msg.content):
        label = item if isinstance(item, Literal) else None
        if isinstance(item, str):
            label = Literal(item)
        if label is not None:
            agent.plans.remove(label)


def _ask_how(agent, msg: Message, sender: Term) -> None:
    content = msg.content
    trigger = content.as_trigger() if isinstance(content, PlanTerm) else None
    if trigger is None and isinstance(content, str):
        from agentspeak.parser import parse_term
        parsed = parse_term("{" + content + "}")
        trigger = parsed.as_trigger() if isinstance(parsed, PlanTerm) else None
    plans = []
    if trigger is not None:
        from agentspeak.unify import unifies
        for p in agent.plans.relevant(trigger):
            if unifies(p.trigger.literal, trigger.literal, {}) or unifies(trigger.literal, p.trigger.literal, {}):
                plans.append(PlanTerm(plan=p))
    _answer(agent, msg, "tellHow", make_list(plans))


_FAST_PATH = frozenset(("tell", "achieve", "signal"))
_ASKS = frozenset(("askOne", "askAll", "askHow"))

_HANDLERS = {
    "tell": _tell, "untell": _untell, "achieve": _achieve, "unachieve": _unachieve,
    "askOne": _ask_one, "askAll": _ask_all, "tellHow": _tell_how, "untellHow": _untell_how,
    "askHow": _ask_how, "signal": _signal,
}

__all__ = ["Message", "receive_message", "PERFORMATIVES", "new_message_id"]
