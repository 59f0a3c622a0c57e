"""Control of goals and intentions: fail, succeed_goal, fail_goal, drop_*, intend, desire, suspend, resume."""
from __future__ import annotations

from agentspeak.intentions import Intention
from agentspeak.program import ACHIEVE, ADD
from agentspeak.stdlib.registry import IAError, Suspend, internal_action
from agentspeak.terms import Literal, resolve
from agentspeak.unify import undo, unifies


@internal_action(".fail", args=(0, None))
def fail(ctx, *annots):
    """Fail the current plan; optional arguments are added to the failure event's annotations."""
    error = "ia_failed"
    message = ".fail"
    extra = []
    for a in annots:
        if isinstance(a, Literal) and a.functor == "error" and a.args:
            error = getattr(a.args[0], "functor", str(a.args[0]))
        elif isinstance(a, Literal) and a.functor == "error_msg" and a.args:
            message = str(a.args[0])
        else:
            extra.append(a)
    raise IAError(error, message, tuple(extra))


def _goal_ims(intention: Intention, goal: Literal):
    """Indexes of intended means (top first) whose trigger is +!goal (goal unifies the trigger)."""
    for i in range(len(intention.stack) - 1, -1, -1):
        im = intention.stack[i]
        t = im.plan.trigger
        if t.op == ADD and t.kind == ACHIEVE and unifies(goal, resolve(t.literal, im.b), {}):
            yield i


def _matching(agent, goal: Literal, current=None):
    """(intention, index) of the top intended means for +!goal, in each intention; ``current`` (the
    intention running the formula, in no queue while it runs) is one of them."""
    intentions = agent.intentions()
    if current is not None and not current.dropped and current not in intentions:
        intentions.append(current)
    for intention in intentions:
        idx = next(_goal_ims(intention, goal), None)
        if idx is not None:
            yield intention, idx


@internal_action(".succeed_goal", args=1)
def succeed_goal(ctx, goal):
    """Finish goal ``goal`` as if its plan had succeeded (the caller goes on after its ``!goal``)."""
    agent = ctx.agent
    _drop_events(agent, goal, "achieved")
    for intention, idx in list(_matching(agent, goal, ctx.intention)):
        finish_at(agent, intention, idx, ctx.intention)
    if ctx.intention is not None and ctx.intention.dropped:
        return Suspend(reason="finished")  # the calling intention itself was finished
    return True


def finish_at(agent, intention, idx: int, current) -> None:
    """The intended means at ``idx`` of ``intention`` is achieved: what it called is dropped and its
    caller goes on (a plan waiting for its goal condition too: pc past the end says achieved)."""
    del intention.stack[idx + 1:]
    intention.waiting = None  # a wait in progress is abandoned
    im = intention.stack[idx]
    im.frames[:] = [im.frames[0]]
    im.frames[0].pc = len(im.frames[0].body) + 1
    if intention is not current:
        agent._requeue(intention)
    agent.clr_int(intention)


@internal_action(".fail_goal", args=1)
def fail_goal(ctx, goal):
    """Abort goal ``goal`` as if its plan had failed (posts ``-!goal``, also for a bottom goal)."""
    agent = ctx.agent
    current = ctx.intention
    affected_current = False
    _fail_pending_events(agent, goal)
    for intention, idx in list(_matching(agent, goal)):
        del intention.stack[idx + 1:]
        if intention is current:
            affected_current = True
            continue
        intention.waiting = None  # a wait in progress is abandoned (its timer must not resume it)
        agent._requeue(intention)
        agent._fail(intention, "ia_failed", f".fail_goal({goal})")
    if affected_current:
        raise IAError("ia_failed", f".fail_goal({goal})")
    return True


def _fail_pending_events(agent, goal: Literal) -> None:
    """A goal still waiting as an event fails there: its -!g (when a plan is relevant) becomes the
    event instead (Jason's generateGoalDeletionFromEvent)."""
    from agentspeak.intentions import Event
    from agentspeak.program import DEL, Trigger
    for ev in list(agent.events):
        t = ev.trigger
        if ev.intention is None and t.op == ADD and t.kind == ACHIEVE and unifies(goal, t.literal, {}):
            agent.events.remove(ev)
            if agent.plans.has_meta:
                agent.goal_state(t, "failed", Literal("ia_failed"))
            failed = Trigger(DEL, ACHIEVE, t.literal)
            if agent.plans.relevant(failed):
                annots = agent._failure_annots("ia_failed", f".fail_goal({goal})")
                lit = t.literal
                for a in annots:
                    lit = lit.add_annot(a)
                agent.events.append(Event(Trigger(DEL, ACHIEVE, lit)))


@internal_action(".drop_intention", args=(0, 1))
def drop_intention(ctx, goal=None):
    """Drop the intention(s) pursuing ``goal`` (no failure event); without argument, the current one."""
    agent = ctx.agent
    if goal is None:
        agent.drop_intention(ctx.intention)
        return Suspend(reason="dropped")
    current_dropped = False
    for intention, _ in list(_matching(agent, goal)):
        if intention is ctx.intention:
            current_dropped = True
        agent.drop_intention(intention)
    return Suspend(reason="dropped") if current_dropped else True


def _drop_events(agent, goal: Literal, state: str = "dropped") -> None:
    """Remove the pending +!goal events (also those .suspend set aside); with meta-event plans, each
    dropped goal reports ``state`` then ``finished`` (Jason's goalFinished)."""
    keep = []
    gone = []
    for ev in agent.events:
        t = ev.trigger
        if t.op == ADD and t.kind == ACHIEVE and unifies(goal, t.literal, {}):
            gone.append(t)
            if ev.intention is not None:
                agent.drop_intention(ev.intention)
            continue
        keep.append(ev)
    agent.events.clear()
    agent.events.extend(keep)
    held = agent.__dict__.get("suspended_events")
    if held:
        for ev in list(held):
            if unifies(goal, ev.trigger.literal, {}):
                held.remove(ev)
                gone.append(ev.trigger)
    if agent.plans.has_meta:
        for t in gone:
            agent.goal_state(t, state)
            agent.goal_state(t, "finished")


def drop_desire(agent, goal: Literal, current=None) -> bool:
    _drop_events(agent, goal)
    dropped_current = False
    for intention, _ in list(_matching(agent, goal)):
        if intention is current:
            dropped_current = True
        agent.drop_intention(intention)
    return dropped_current


@internal_action(".drop_desire", args=1)
def drop_desire_(ctx, goal):
    """Remove goal ``goal`` from events and intentions."""
    return Suspend(reason="dropped") if drop_desire(ctx.agent, goal, ctx.intention) else True


def _drop_other_intentions(ctx) -> None:
    """Jason's drop_all_intentions: every intention but the calling one (Jason runs it outside the queue
    it empties), the events those intentions posted, and the events ``.at`` would post (``cancelAts``).
    A ``!!g``'s event stays, as the environment's and messages' do: it belongs to no intention."""
    agent = ctx.agent
    for i in agent.intentions():
        if i is not ctx.intention:
            agent.drop_intention(i)
    kept = [ev for ev in agent.events if ev.intention is None or ev.intention is ctx.intention]
    if len(kept) != len(agent.events):
        agent.events.clear()
        agent.events.extend(kept)
    for pending in getattr(agent, "at_events", None) or ():  # Jason's at.cancelAts (.at: stdlib/mas.py)
        pending.cancelled = True
    agent.at_events = set()


@internal_action(".drop_all_desires", args=0)
def drop_all_desires(ctx):
    """Jason's drop_all_intentions and every event (the calling intention goes on)."""
    _drop_other_intentions(ctx)
    ctx.agent.events.clear()


@internal_action(".drop_all_intentions", args=0)
def drop_all_intentions(ctx):
    """Drop every intention but the calling one, their events and the pending ``.at`` events (Jason 3.3:
    "all intentions except the one where .drop_all_intentions appears are dropped")."""
    _drop_other_intentions(ctx)


@internal_action(".drop_all_events", args=0)
def drop_all_events(ctx):
    ctx.agent.events.clear()


def _failing(agent, intention: Intention) -> set:
    """The intended means whose goal is being failed (a -!g event or plan handles it): no longer a
    desire (Jason pops them with the failure)."""
    out = {id(im.handles) for im in intention.stack if im.handles is not None}
    for ev in agent.events:
        if ev.intention is intention and ev.handles is not None:
            out.add(id(ev.handles))
    return out


@internal_action(".intend", args=(1, 2))
def intend(ctx, goal, ident=None):
    """Is ``goal`` currently intended? Backtracks over intentions (not over those .suspend set aside)."""
    return _intended(ctx, goal, ident, False)


def _intended(ctx, goal, ident, with_suspended: bool):
    for intention in ctx.agent.intentions() + ([ctx.intention] if ctx.intention and ctx.intention.dropped is False and ctx.intention not in ctx.agent.intentions() else []):
        if not with_suspended and intention.suspended == "suspended" and intention is not ctx.intention:
            continue  # Jason's .intend leaves out the intentions .suspend set aside (not those waiting)
        failing = _failing(ctx.agent, intention)
        for i in _goal_ims(intention, goal):
            im = intention.stack[i]
            if id(im) in failing:
                continue
            mark = len(ctx.trail)
            if ctx.unify(goal, resolve(im.plan.trigger.literal, im.b)) and (ident is None or ctx.unify(ident, intention.id)):
                yield
            undo(ctx.b, ctx.trail, mark)


@internal_action(".desire", args=(1, 2))
def desire(ctx, goal, ident=None):
    """Is ``goal`` a desire (a pending goal event, one set aside by .suspend, or an intention)?"""
    for ev in list(ctx.agent.events) + list(ctx.agent.__dict__.get("suspended_events", ())):
        t = ev.trigger
        if t.op == ADD and t.kind == ACHIEVE:
            mark = len(ctx.trail)
            if ctx.unify(goal, t.literal):
                yield
            undo(ctx.b, ctx.trail, mark)
    yield from _intended(ctx, goal, ident, True)


@internal_action(".suspend", args=(0, 1))
def suspend(ctx, goal=None):
    """Suspend the intention(s) pursuing ``goal`` until ``.resume(goal)`` (the current one without argument)."""
    agent = ctx.agent
    if goal is None:
        return Suspend(reason="suspended")
    current = False
    # a goal not yet intended (its event is pending) is set aside until .resume (Jason's PE)
    held = agent.__dict__.setdefault("suspended_events", [])
    for ev in list(agent.events):
        t = ev.trigger
        if ev.intention is None and t.op == ADD and t.kind == ACHIEVE and unifies(goal, t.literal, {}):
            agent.events.remove(ev)
            held.append(ev)
    for intention, _ in list(_matching(agent, goal)):
        if intention is ctx.intention:
            current = True
            continue
        try:
            agent.running.remove(intention)
        except ValueError:
            pass
        agent._suspend(intention, "suspended")
        before = intention.waiting
        held = Suspend(reason="suspended", term=getattr(before, "term", None))
        held.inner = before  # a wait in progress: it completes only once resumed
        intention.waiting = held
    if agent.plans.has_meta:
        from agentspeak.program import Trigger
        agent.goal_state(Trigger(ADD, ACHIEVE, goal), "suspended")
    return Suspend(reason="suspended") if current else True


@internal_action(".resume", args=1)
def resume(ctx, goal):
    """Resume intentions suspended by ``.suspend`` that pursue ``goal``. One that was waiting (``.wait``,
    an action) goes on waiting; the resumed intention runs after the resuming one's next step (it is
    queued at the next cycle, as Jason puts it back at the end of the intentions)."""
    agent = ctx.agent
    resumed = False
    pending = agent.__dict__.get("suspended_events")
    for ev in list(pending or ()):
        if unifies(goal, ev.trigger.literal, {}):
            pending.remove(ev)
            agent.post_feedback(lambda e=ev: agent.events.append(e))
            resumed = True
    for intention, _ in list(_matching(agent, goal)):
        if intention.suspended == "suspended":
            held = intention.waiting
            agent.post_feedback(lambda i=intention, h=held: _resume(agent, i, h))
            resumed = True
    if resumed and agent.plans.has_meta:
        from agentspeak.program import Trigger
        agent.goal_state(Trigger(ADD, ACHIEVE, goal), "resumed")


def _resume(agent, intention, held) -> None:
    if intention.dropped or intention.waiting is not held:
        return
    complete = getattr(held, "complete", None)
    inner = getattr(held, "inner", None)
    if complete is not None:       # the wait ended meanwhile: go on after it
        complete()
    elif inner is not None:        # still waiting: the wait goes on
        intention.waiting = inner
        intention.suspended = inner.reason
    else:
        finish = getattr(held, "finish", None)
        if finish is not None:
            finish(True)
        else:
            intention.waiting = None
            agent._requeue(intention)


@internal_action(".suspended", args=2)
def suspended(ctx, goal, reason):
    """``.suspended(G, R)``: G is the goal of a suspended intention and R why (``wait(W)[time(T)]`` for a
    ``.wait``, ``suspended`` for ``.suspend``, else the kind of wait)."""
    for intention in ctx.agent.intentions():
        if intention.suspended:
            for i in _goal_ims(intention, goal):
                term = getattr(intention.waiting, "term", None)
                mark = len(ctx.trail)
                if ctx.unify(goal, resolve(intention.stack[i].plan.trigger.literal, intention.stack[i].b)) and \
                        ctx.unify(reason, term if term is not None else Literal(intention.suspended)):
                    yield
                    return
                undo(ctx.b, ctx.trail, mark)
