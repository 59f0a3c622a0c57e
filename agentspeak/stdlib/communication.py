"""Messages: send, broadcast, my_name, all_names (KQML semantics in agentspeak.communication)."""
from __future__ import annotations

from concurrent.futures import Future

from agentspeak.communication import Message, stamp_sent
from agentspeak.stdlib.registry import IAError, Suspend, internal_action, wrong_arguments
from agentspeak.terms import NIL, Literal, Var, list_items, make_list, to_str

_ASK = ("askOne", "askAll", "askHow")
_new = object.__new__  # a Message without the class call: see agentspeak.agent._new


def _names(receiver) -> list[str]:
    if type(receiver) is Literal and not receiver.args:
        return [receiver.functor]  # the usual single receiver
    try:
        items = list_items(receiver)
    except TypeError:
        items = [receiver]
    names = []
    for r in items:
        if isinstance(r, Literal) and not r.args:
            names.append(r.functor)
        elif isinstance(r, str):
            names.append(r)
        else:
            raise wrong_arguments(f".send: '{to_str(r)}' is not an agent name")
    return names


@internal_action(".send", args=(3, 5))
def send(ctx, receiver, performative, content, answer=None, timeout=None):
    """``.send(R, Perf, C[, Ans[, TimeoutMs]])``. With Ans, an ask suspends this intention until
    the answer (``false`` if unknown, ``timeout`` on timeout) - other intentions go on."""
    agent = ctx.agent
    if (answer is None and type(receiver) is Literal and not receiver.args and type(performative) is Literal
            and not performative.args and type(content) is not Var):
        # the usual send: one receiver named by an atom, no answer awaited (the checks below pass)
        msg = Message.__new__(Message)  # Message(agent.name, receiver.functor, performative.functor, content)
        msg.sender, msg.receiver, msg.performative = agent.name, receiver.functor, performative.functor
        msg.content, msg._msg_id, msg.in_reply_to, msg.sent_at, msg.read_at = content, None, None, None, None
        if agent.arch.send(agent, msg) is False:
            raise receiver_not_found(msg)
        return True
    if not isinstance(performative, Literal) or performative.args:
        raise wrong_arguments(".send: the performative must be an atom")
    perf = performative.functor
    names = (receiver.functor,) if type(receiver) is Literal and not receiver.args else _names(receiver)
    if isinstance(content, Var):
        raise wrong_arguments(".send: the content is an unbound variable")
    sender = agent.name
    if answer is None or perf not in _ASK:
        for name in names:
            msg = Message(sender, name, perf, content)
            if answer is not None and not isinstance(answer, Var):
                # .send(S, tell, C, MsgId): the reply to the ask MsgId (Jason's 4th argument of a tell)
                msg.in_reply_to = answer if isinstance(answer, str) else to_str(answer)
            if agent.arch.send(agent, msg) is False:
                raise receiver_not_found(msg)
        return True
    # a synchronous ask: wait for the replies
    if timeout is not None and not isinstance(timeout, (int, float)):
        raise wrong_arguments(".send: the timeout is a number of milliseconds")
    futures = []
    asks = set()  # the ids of the messages this ask sent
    for name in names:
        msg = Message(sender, name, perf, content)
        if timeout is not None:
            stamp_sent(msg)  # a deadline runs: the receiver reads it first (LocalRuntime._route_from)
        asks.add(msg.msg_id)
        fut: Future = Future()
        futures.append(fut)

        def on_reply(reply: Message, fut=fut, name=name) -> None:
            if not fut.done():
                fut.set_result(reply)
        agent.pending_asks[msg.msg_id] = on_reply
        if agent.arch.send(agent, msg) is False:
            for asked in asks:
                agent.pending_asks.pop(asked, None)
            raise receiver_not_found(msg)
    waiting = _all_of(futures)

    def on_result(c, replies) -> bool:
        values = [_answer_value(perf, r, content) for r in replies]
        value = values[0] if len(values) == 1 and not isinstance(receiver, type(NIL)) and len(names) == 1 and not _is_list(receiver) else make_list(values)
        if not c.unify(answer, value):  # Jason's TransitionSystem.resumeSyncAskIntention
            raise IAError("ask_failed", f"reply of an ask message ('{to_str(value)}') does not unify with fourth "
                                        f"argument of .send ('{to_str(answer, c.b)}')")
        return True

    def forget() -> None:
        """No answer is awaited any more (timed out, or the intention dropped): their entries go, or each such
        ask would keep its callback, future and lock for as long as the agent runs (issue 22's soak)."""
        for asked in asks:
            agent.pending_asks.pop(asked, None)

    def on_timeout(c) -> bool:
        forget()
        for fut in futures:
            fut.cancel()
        c.unify(answer, Literal("timeout"))  # Jason goes on even when the answer pattern does not match
        return True

    seconds = None if timeout is None else timeout / 1000.0

    def answer_waiting(deadline: float) -> bool:
        # an answer sent in time but not read yet (this agent got no CPU meanwhile) is not a timeout
        for m in agent.mailbox:
            sent = getattr(m, "sent_at", None)
            if m.in_reply_to in asks and sent is not None and sent <= deadline:
                return True
        return False
    return Suspend(future=waiting, on_result=on_result, timeout=seconds,
                   on_timeout=on_timeout if seconds is not None else None, reason="ask",
                   answer_waiting=answer_waiting if seconds is not None else None, on_drop=forget)


def receiver_not_found(message: Message) -> IAError:
    """Jason's ``ReceiverNotFoundException`` (``LocalAgArch.sendMsg``): no agent of that name in the MAS (never
    was, or killed, or its process gone), so ``.send`` fails with ``error(receiver_not_found)`` and
    ``agent_not_found(Name)`` rather than the message being lost unnoticed."""
    return IAError("receiver_not_found", f"Receiver '{message.receiver}' does not exist! Could not send {message}",
                   (Literal("agent_not_found", (Literal(message.receiver),)),))


def _is_list(t) -> bool:
    try:
        list_items(t)
        return True
    except TypeError:
        return False


def _all_of(futures: list[Future]) -> Future:
    done: Future = Future()
    remaining = [len(futures)]
    results: list = [None] * len(futures)

    def one(i: int, f: Future) -> None:
        if f.cancelled():
            return
        results[i] = f.result()
        remaining[0] -= 1
        if remaining[0] == 0 and not done.done():
            done.set_result(results)
    for i, f in enumerate(futures):
        f.add_done_callback(lambda f, i=i: one(i, f))
    return done


def _answer_value(perf: str, reply: Message, question):
    """What the asker's answer variable gets: the content annotated with the replier as source."""
    sender = Literal(reply.sender)
    if reply.performative == "untell":
        return Literal("false")
    content = reply.content
    if perf == "askHow":
        return content
    if perf == "askAll":
        try:
            return make_list([_with_source(c, sender) for c in list_items(content)])
        except TypeError:
            return content
    return _with_source(content, sender)


def _with_source(t, sender):
    if isinstance(t, Literal):
        from agentspeak.communication import nested_source
        return nested_source(t, sender)
    return t


@internal_action(".broadcast", args=2)
def broadcast(ctx, performative, content):
    """Send to every other agent of the MAS."""
    agent = ctx.agent
    if not isinstance(performative, Literal):
        raise wrong_arguments(".broadcast: the performative must be an atom")
    for name in agent.arch.all_names(agent):
        if name != agent.name:
            agent.arch.send(agent, Message(agent.name, name, performative.functor, content))


@internal_action(".my_name", args=1)
def my_name(ctx, name):
    return ctx.unify(name, Literal(ctx.agent.name))


@internal_action(".all_names", args=1)
def all_names(ctx, result):
    return ctx.unify(result, make_list([Literal(n) for n in sorted(ctx.agent.arch.all_names(ctx.agent))]))


