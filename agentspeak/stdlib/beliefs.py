"""Queries and belief-base actions: findall, setof, count, abolish, asserta/assertz, belief."""
from __future__ import annotations

from agentspeak.beliefs import SOURCE_SELF, has_source
from agentspeak.program import ADD, BEL, DEL, Trigger
from agentspeak.stdlib.lists import _set
from agentspeak.stdlib.registry import internal_action, wrong_arguments
from agentspeak.terms import Literal, is_ground, make_list, resolve
from agentspeak.unify import undo


def _solutions(ctx, template, query) -> list:
    """Every instance of ``template`` for the solutions of ``query`` (bindings left untouched)."""
    out = []
    b = dict(ctx.b)
    from agentspeak.solver import solve
    for _ in solve(ctx.agent, query, b):
        out.append(resolve(template, b))
    return out


@internal_action(".findall", args=3)
def findall(ctx, template, query, result):
    """All instances of ``template`` for which ``query`` holds, in belief-base order."""
    return ctx.unify(result, make_list(_solutions(ctx, template, query)))


@internal_action(".setof", args=3)
def setof(ctx, template, query, result):
    """Like ``.findall`` but sorted and without duplicates."""
    return ctx.unify(result, make_list(_set(_solutions(ctx, template, query))))


@internal_action(".count", args=2)
def count(ctx, query, result):
    """Number of solutions of ``query``."""
    return ctx.unify(result, len(_solutions(ctx, query, query)))


@internal_action(".abolish", args=1)
def abolish(ctx, pattern):
    """Remove every belief that unifies with ``pattern`` (posting -b events)."""
    agent = ctx.agent
    from agentspeak.terms import DEFAULT_NS_NAME, AnnotatedVar, NsTerm, Var
    from agentspeak.unify import unifies
    if isinstance(pattern, Var):  # `_`, `X`, `_[source(a)]`: any belief (with these annotations) of the
        # default name space, the variable's (Jason's Agent.abolish unifies the pattern with every belief)
        facts = agent.bb.in_namespace(DEFAULT_NS_NAME)
    elif isinstance(pattern, NsTerm):  # `ns::_`, `N::b(_)`: the beliefs of a name space, of every one
        facts = agent.bb.in_every_ns(pattern.body)[0]
    elif isinstance(pattern, Literal):
        facts = list(agent.bb.candidates(pattern, {}))
    else:
        raise wrong_arguments(".abolish needs a literal")
    for fact in facts:
        if unifies(pattern, fact, {}):
            removed = agent.bb.remove(fact)
            if removed is not None:
                agent.post_external(Trigger(DEL, BEL, removed))


def _assert(ctx, term, at_end: bool):
    agent = ctx.agent
    from agentspeak.program import PlanTerm
    if isinstance(term, PlanTerm) and term.rule is not None:
        agent.bb.add_rule(term.rule, at_end=at_end)
        return True
    if not isinstance(term, Literal) or not is_ground(term):
        raise wrong_arguments("assert needs a ground literal or a rule {h :- b}")
    if not has_source(term):
        term = term.add_annot(SOURCE_SELF)
    added = agent.bb.add(term, at_end=at_end)
    if added is not None:
        agent.post_external(Trigger(ADD, BEL, added))
    return True


@internal_action(".asserta", args=1)
def asserta(ctx, term):
    return _assert(ctx, term, False)


@internal_action(".assertz", args=1)
def assertz(ctx, term):
    return _assert(ctx, term, True)


@internal_action(".belief", args=1)
def belief(ctx, pattern):
    """Query facts only (no rules), backtracking."""
    from agentspeak.unify import unify
    for fact in list(ctx.agent.bb.candidates(pattern, ctx.b)):
        mark = len(ctx.trail)
        if unify(pattern, fact, ctx.b, ctx.trail):
            yield
        undo(ctx.b, ctx.trail, mark)


