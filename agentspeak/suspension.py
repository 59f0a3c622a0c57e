"""Intentions that wait: a body formula whose internal action or action returned a ``Suspend`` (``.wait``, an ask,
an action on a robot, ``.suspend``) stops its intention until an event, a condition, a future or a timeout says
it may go on, then the formula succeeds or fails (Jason's suspended intentions, ``C.PA``/``C.PI``).

Part of the reasoning cycle (``agentspeak.agent``), kept here so that the cycle's file holds its steps (sense,
deliberate, act) and this one everything about waiting. ``ag: Agent`` is ``agentspeak.agent.Agent``, named but
not imported: the agent imports this module. Runs from source (not in ``_speedups.COMPILED_MODULES``): it runs
once per wait, and per cycle only while an intention waits for a condition (``.wait(Cond)``).
"""
from __future__ import annotations

import time
from concurrent.futures import Future

from agentspeak.body import IAContext
from agentspeak.intentions import IntendedMeans, Intention
from agentspeak.program import ACHIEVE, ADD, Trigger
from agentspeak.stdlib.registry import IAError, Suspend
from agentspeak.terms import Literal, resolve
from agentspeak.unify import unify


def suspend_on(ag: Agent, intention: Intention, im: IntendedMeans, susp: Suspend, instr) -> None:
    """Suspend ``intention`` until ``susp`` says it may go on (then the formula succeeds or fails)."""
    ag._suspend(intention, susp.reason)
    intention.waiting = susp
    done = [False]

    def finish(ok: bool, error: str = "ia_failed", message: str = "", extra: tuple = ()) -> None:
        if done[0] or intention.dropped:
            return
        done[0] = True
        # ended otherwise (timeout, future): its waiter must go, or a later matching event would
        # "resume" an intention that has moved on or finished (an IndexError that killed the agent)
        if susp.event is not None:
            ag.event_waiters = [w for w in ag.event_waiters if w[2] is not susp]
        if susp.until is not None:
            ag.condition_waiters = [w for w in ag.condition_waiters if w[1] is not susp]
        held = intention.waiting
        if held is not susp:
            if held is not None and getattr(held, "inner", None) is susp:
                # suspended by .suspend while waiting (Jason keeps it pending): .resume completes this
                held.complete = lambda: complete(ok, error, message, extra)
            # else the wait was abandoned (its goal failed or succeeded meanwhile)
            return
        complete(ok, error, message, extra)

    def complete(ok: bool, error: str, message: str, extra: tuple) -> None:
        intention.waiting = None
        if ok:
            ag._advance(im)
            ag._requeue(intention)
            ag.clr_int(intention)
        else:
            # Not back in the run queue: _fail either suspends the intention on its -!g event
            # or drops it. Requeued, it would run the failed formula again before the event.
            intention.suspended = None
            ag.suspended.pop(intention.id, None)
            ag._fail(intention, error, message or f"{instr} failed", instr, extra=extra)

    susp.finish = finish  # type: ignore[attr-defined]
    if ag.plans.has_meta:
        for gim in reversed(intention.stack):
            t = gim.plan.trigger
            if t.op == ADD and t.kind == ACHIEVE:
                ag.goal_state(Trigger(ADD, ACHIEVE, resolve(gim.event_literal, gim.b)), "waiting",
                                susp.term if susp.term is not None else Literal(susp.reason))
                break
    ctx = IAContext(ag, intention, im, im.b, [])
    if susp.future is not None:
        ag.pending_futures += 1

        def on_done(fut: Future) -> None:
            def apply() -> None:
                ag.pending_futures -= 1
                if done[0]:
                    return
                try:
                    value = fut.result()
                except Exception as exc:  # the awaited work failed: the formula fails with its reason
                    finish(False, "ia_failed", f"{instr}: {exc}")
                    return
                try:
                    ok = susp.on_result(ctx, value) if susp.on_result else True
                except IAError as exc:
                    finish(False, exc.error, exc.message, exc.annots)
                    return
                finish(bool(ok) or ok is None)
            ag.feedback.append(apply)
            ag.arch.wake(ag)
        susp.future.add_done_callback(on_done)
    if susp.timeout is not None:
        # answers are stamped in wall time; on an environment's clock the timeout's wall time is when it fires
        deadline = time.monotonic() + susp.timeout if ag.clock == time.monotonic else None

        def on_timeout() -> None:
            if done[0]:
                return
            if susp.answer_waiting is not None and \
                    susp.answer_waiting(deadline if deadline is not None else time.monotonic()):
                ag.add_timer(0.0, on_timeout)  # again once the answer in the mailbox is read
                return
            if susp.on_timeout is not None:
                try:
                    ok = susp.on_timeout(ctx)
                except IAError as exc:
                    finish(False, exc.error, exc.message)
                    return
                finish(bool(ok), "timeout", f"{instr} timed out")
            else:
                finish(False, "timeout", f"{instr} timed out after {susp.timeout} s")
            if susp.future is not None and not susp.future.done():
                susp.future.cancel()
        ag.add_timer(susp.timeout, on_timeout)
    if susp.event is not None:
        ag.event_waiters.append((susp.event, intention, susp))
    if susp.until is not None:
        ag.condition_waiters.append((intention, susp))


def notify_waiters(ag: Agent, trigger: Trigger) -> None:
    """An event happened: resume the intentions waiting for one that unifies with it (``.wait({+b})``)."""
    if not ag.event_waiters:
        return
    for entry in list(ag.event_waiters):
        pattern, intention, susp = entry
        b = dict(intention.stack[-1].b) if intention.stack else {}
        trail: list = []
        if pattern.op == trigger.op and pattern.kind == trigger.kind and unify(pattern.literal, trigger.literal, b, trail):
            ag.event_waiters.remove(entry)
            im = intention.stack[-1]
            im.b.update(b)
            resume(susp, True)


def resume(susp: Suspend, ok: bool) -> None:
    """Let a suspended formula go on (``ok``) or fail, through what ``suspend_on`` set up for it."""
    finish = getattr(susp, "finish", None)
    if finish is not None:
        finish(ok)


def check_conditions(ag: Agent) -> None:
    """Once per cycle: resume the intentions waiting until a condition holds (``.wait(Cond)``)."""
    for entry in list(ag.condition_waiters):
        intention, susp = entry
        try:
            holds = susp.until()
        except Exception:  # a broken condition must not stop the agent
            holds = False
        if holds:
            ag.condition_waiters.remove(entry)
            resume(susp, True)
