"""Plan library actions: add_plan, remove_plan, relevant_plans, plan_label, list_plans."""
from __future__ import annotations

from agentspeak.program import PlanTerm
from agentspeak.stdlib.registry import IAError, internal_action, wrong_arguments
from agentspeak.terms import Literal, Term, list_items, make_list, to_str


def add_plan_term(agent, term: Term, source: Term, at_end: bool = True) -> None:
    """Add a plan given as a term (``{...}``), a string of AgentSpeak, or a list of those."""
    from agentspeak.parser import parse_plans
    if isinstance(term, str):
        plans = parse_plans(term, "<added plan>")
    elif isinstance(term, PlanTerm):
        if term.rule is not None:
            agent.bb.add_rule(term.rule, at_end=at_end)
            return
        plan = term.as_plan()
        if plan is None:
            raise wrong_arguments(f"'{term}' is not a plan")
        plans = [plan.renamed()]
    else:
        try:
            for item in list_items(term):
                add_plan_term(agent, item, source, at_end)
            return
        except TypeError:
            raise wrong_arguments(f"'{to_str(term)}' is not a plan") from None
    for plan in plans:
        label = plan.ensure_label()
        annots = tuple(a for a in label.annots or () if not (isinstance(a, Literal) and a.functor == "source"))
        plan.label = Literal(label.functor, label.args, annots + (Literal("source", (source,)),))
        plan.refresh_label_flags()
        agent.plans.add(plan, at_end=at_end)


@internal_action(".add_plan", args=(1, 3))
def add_plan(ctx, plans, source=None, position=None):
    """``.add_plan(P[, Source, begin|end])``: P is a plan term, a string, or a list of them."""
    at_end = not (isinstance(position, Literal) and position.functor == "begin")
    add_plan_term(ctx.agent, plans, source if source is not None else Literal("self"), at_end)


@internal_action(".remove_plan", args=(1, 2))
def remove_plan(ctx, labels, source=None):
    """Remove plans by label (an atom, a term, or a list of labels)."""
    try:
        items = list_items(labels)
    except TypeError:
        items = [labels]
    for label in items:
        if isinstance(label, PlanTerm):  # a plan term stands for its label (Jason)
            plan = label.as_plan()
            if plan is None or plan.label is None:
                raise IAError("ia_failed", f".remove_plan({label}): a plan is removed by its label, "
                                           f"and this plan term has none")
            label = plan.label
        if isinstance(label, str):
            label = Literal(label[1:] if label.startswith("@") else label)
        if isinstance(label, Literal):
            ctx.agent.plans.remove(label, source)


@internal_action(".relevant_plans", args=(2, 3))
def relevant_plans(ctx, trigger_term, result, labels=None):
    """The plans relevant for a trigger ``{+!g}``, as plan terms with fresh variables (Jason returns
    copies: a copy bound into the running plan must not share its variables), and their labels."""
    trigger = trigger_term.as_trigger() if isinstance(trigger_term, PlanTerm) else None
    if trigger is None:
        raise wrong_arguments(".relevant_plans needs a trigger term such as {+!g}")
    from agentspeak.unify import unifies
    found = [p for p in ctx.agent.plans.relevant(trigger)
             if p.trigger.op == trigger.op and p.trigger.kind == trigger.kind
             and unifies(p.trigger.literal, trigger.literal, {})]
    ok = ctx.unify(result, make_list([PlanTerm(plan=p).rename({}) for p in found]))
    if ok and labels is not None:
        ok = ctx.unify(labels, make_list([p.ensure_label() for p in found]))
    return ok


@internal_action(".plan_label", args=2)
def plan_label(ctx, plan, label):
    """``.plan_label(P, L)``: the plan (as a term) of label L, or the label of plan term P, or, both
    free, backtracks over every plan (Jason's three modes)."""
    from agentspeak.terms import Var
    from agentspeak.unify import undo
    if isinstance(plan, Var) and not isinstance(label, Var):
        name = label.functor if isinstance(label, Literal) else to_str(label)
        p = ctx.agent.plans.by_label(name)
        return p is not None and ctx.unify(plan, PlanTerm(plan=p).rename({}))
    if isinstance(label, Var) and isinstance(plan, PlanTerm) and plan.plan is not None:
        return plan.plan.label is not None and ctx.unify(label, plan.plan.label)
    return _all_plan_labels(ctx, plan, label, undo)


def _all_plan_labels(ctx, plan, label, undo):
    for p in list(ctx.agent.plans):
        mark = len(ctx.trail)
        if ctx.unify(label, p.ensure_label()) and ctx.unify(plan, PlanTerm(plan=p).rename({})):
            yield
        undo(ctx.b, ctx.trail, mark)


@internal_action(".list_plans", args=(0, 1))
def list_plans(ctx, trigger_term=None):
    trigger = trigger_term.as_trigger() if isinstance(trigger_term, PlanTerm) else None
    plans = ctx.agent.plans.relevant(trigger) if trigger is not None else list(ctx.agent.plans)
    for p in plans:
        ctx.agent.arch.print_line(ctx.agent, str(p) + ".")


