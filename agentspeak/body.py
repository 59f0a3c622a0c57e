"""The body formulas: what ``Agent.act`` executes, ONE formula per reasoning cycle (Jason's rule ExecInt
and its cases), one ``_exec_*`` per kind of formula, chosen by ``_DISPATCH``; and ``IAContext``, what an
internal action sees.

Moved unchanged from ``agentspeak/agent.py`` (issue 23), which keeps the cycle itself (sense, deliberate,
act), with ``fresh_goal``, the literal a goal formula posts; waiting is ``agentspeak/suspension.py``. ``ag: Agent`` is ``agentspeak.agent.Agent``, named but not imported: the agent imports this module.
Compiled with the interpreter (``body.pxd``).
"""
from __future__ import annotations

from concurrent.futures import Future
from typing import Iterator

from agentspeak import program as P
from agentspeak.beliefs import SELF, SOURCE_SELF, has_source
from agentspeak.intentions import Event, Frame, IntendedMeans, Intention
from agentspeak.program import ACHIEVE, ADD, BEL, DEL, TEST, PlanTerm, Trigger
from agentspeak.solver import _COMPILED, _true_k, compiled, solve, solve_first
from agentspeak.stdlib.registry import IAError, Suspend, yields_solutions
from agentspeak.terms import (
    _EXACT, INT_OPS, Arith, Literal, NsTerm, Term, Var, is_ground, rename, resolve, to_str, variables,
)
from agentspeak.unify import undo, unify

_new = object.__new__
"""Hot paths build objects with ``_new(Class)`` (or ``Class.__new__(Class)`` for the classes that the
compiled build makes C types, see agent.pxd: ``object.__new__`` refuses those) and slot stores: a class
call costs ~150 ns more in CPython 3.11 (a ring hop makes eight such objects).
tests/agentspeak/test_message_path.py checks that every slot gets set, so a slot added to one of these
classes must be set there too."""


class IAContext:
    """What an internal action sees: the agent, the calling intention, and the bindings. A body formula
    builds it without ``__init__`` (see ``_new``)."""

    __slots__ = ("agent", "intention", "im", "b", "trail")

    def __init__(self, agent: "Agent", intention: Intention | None, im: IntendedMeans | None,
                 b: dict, trail: list) -> None:
        self.agent, self.intention, self.im, self.b, self.trail = agent, intention, im, b, trail

    def unify(self, a: Term, c: Term) -> bool:
        mark = len(self.trail)
        if unify(a, c, self.b, self.trail):
            return True
        undo(self.b, self.trail, mark)
        return False

    def resolve(self, t: Term) -> Term:
        return resolve(t, self.b)

    def solve(self, formula: Term) -> Iterator[None]:
        return solve(self.agent, formula, self.b, self.trail)


def _exec_achieve(ag: Agent, intention: Intention, im: IntendedMeans, frame: Frame, instr) -> None:
    trigger = Trigger(ADD, ACHIEVE, fresh_goal(instr.term, im.b))
    if ag.event_waiters:  # post_internal, inlined: this is the step of every subgoal
        ag._notify_waiters(trigger)
    if ag.plans.has_meta:
        ag.goal_state(trigger, "pending")
    ag.events.append(Event(trigger, intention))
    intention.suspended = "event"


def _exec_achieve_new(ag: Agent, intention, im, frame, instr) -> None:
    lit = fresh_goal(instr.term, im.b)
    ag.post_external(Trigger(ADD, ACHIEVE, lit), force=True)
    frame.pc += 1


def _exec_test(ag: Agent, intention, im, frame, instr) -> None:
    query = instr.term
    if solve_first(ag, query, im.b):
        frame.pc += 1
        return
    value = resolve(query, im.b)
    if type(value) is Literal and ag.plans.relevant(Trigger(ADD, TEST, value)):
        lit = fresh_goal(value, im.b)
        ag.post_internal(Trigger(ADD, TEST, lit), intention)
        return
    raise IAError("test_goal_failed", f"test goal '{to_str(value)}' failed")


_SOURCE_SELF_ONLY = (SOURCE_SELF,)


def fresh_goal(lit: Term, b: dict) -> Term:
    """The literal of a goal event (``!g``, ``?g`` with plans, ``!!g``, ``.at``, an initial goal; Jason's
    prepareBodyForEvent): apply bindings, rename unbound variables apart (binding the caller's to the new ones),
    and add ``source(self)``."""
    if type(lit) is Literal and lit.annots is None and lit.annot_tail is None:
        # the usual goal: arguments that resolve to numbers, strings or atoms; built once
        args = []
        for a in lit.args:
            ta = type(a)
            if ta is Var:
                a = b.get(a, a)
                ta = type(a)
            if ta is not int and ta is not float and ta is not str:
                if ta is Arith and a.right is not None and a.op in INT_OPS:
                    # `N + 1` over integers (resolve's own fast case, without the call)
                    x, y = a.left, a.right
                    if type(x) is Var:
                        x = b.get(x, x)
                    if type(y) is Var:
                        y = b.get(y, y)
                    if type(x) is int and type(y) is int:
                        r = INT_OPS[a.op](x, y)
                        if -_EXACT < r < _EXACT:
                            args.append(r)
                            continue
                a = resolve(a, b)
                ta = type(a)
                if not (ta is int or ta is float or ta is str
                        or (ta is Literal and not a.args and a.annots is None)):
                    break
            args.append(a)
        else:
            return Literal(lit.functor, tuple(args), _SOURCE_SELF_ONLY, lit.neg)
    value = resolve(lit, b)
    if type(value) is Literal:
        if value.annots or value.annot_tail is not None or not constant_args(value.args):
            vs = variables(value)
            if vs:
                mapping: dict = {}
                value = rename(value, mapping)
                for old, new in mapping.items():
                    b[old] = new
        if not value.annots or not has_source(value):
            value = value.add_annot(SOURCE_SELF)
    elif type(value) is Var:
        raise IAError("wrong_arguments", f"unbound variable {value.name} used as a goal")
    elif type(value) is NsTerm:
        raise IAError("wrong_arguments", f"the name space of the goal {to_str(value)} is unbound")
    return value


def bindings_free(lit: Term) -> bool:
    """True for a literal that ``resolve`` would only copy: its arguments numbers, strings and atoms, its
    annotations literals of those (a goal's ``g(1, 2)[source(self)]``)."""
    if type(lit) is not Literal or lit.annot_tail is not None or not constant_args(lit.args):
        return False
    for a in lit.annots or ():
        if type(a) is not Literal or a.annots is not None or a.annot_tail is not None or not constant_args(a.args):
            return False
    return True


def constant_args(args: tuple) -> bool:
    """Every argument is a number, a string or an atom (so a literal of them is ground and has no variable)."""
    for a in args:
        ta = type(a)
        if not (ta is int or ta is float or ta is str
                or (ta is Literal and not a.args and a.annots is None and a.annot_tail is None)):
            return False
    return True


def _belief_literal(term: Term, b: dict) -> Literal:
    if type(term) is Literal and term.annots is None and term.annot_tail is None:
        # the usual `+b(I, J)`: arguments that are (or are bound to) numbers, strings or atoms; the belief with
        # its source(self) built at once (what resolve, then add_annot, would build)
        args = []
        for a in term.args:
            ta = type(a)
            if ta is Var:
                a = b.get(a, a)
                ta = type(a)
            if ta is int or ta is float or ta is str or (ta is Literal and not a.args and a.annots is None
                                                         and a.annot_tail is None):
                args.append(a)
                continue
            break
        else:
            lit = _new(Literal)
            lit.functor, lit.args, lit.annots = term.functor, tuple(args), _SOURCE_SELF_ONLY
            lit.neg, lit.annot_tail, lit._hash = term.neg, None, None
            return lit
    lit = resolve(term, b)
    if type(lit) is not Literal:
        raise IAError("wrong_arguments", f"'{to_str(lit)}' is not a literal")
    if not is_ground(lit):
        # Jason stores a belief with free variables as it is (`+test(T,failed)`); here with variables of
        # its own, so the belief never shares (or binds) the plan's variables
        lit = rename(lit, {})
    if not has_source(lit):
        lit = lit.add_annot(SOURCE_SELF)
    return lit


def _in_scope(intention: Intention) -> bool:
    """The intention's top plan has sub-plans or is one (a sub-plan may react to its +b/-b)."""
    plan = intention.stack[-1].plan if intention.stack else None
    return plan is not None and (plan.sub_library is not None or plan.scope is not None)


def _post_belief_event(ag: Agent, trigger: Trigger, intention: Intention, new_focus: bool) -> None:
    """A +b/-b from a plan body: on the same intention (it waits for the event) when a plan is
    relevant, a new intention for ``++b``/``--b``; with no relevant plan the intention just goes on."""
    if new_focus:
        ag.post_external(trigger)
    elif ag.plans.relevant(trigger) or (ag.plans.has_update_sub_plans and _in_scope(intention)):
        ag.post_internal(trigger, intention)
    else:
        ag._notify_waiters(trigger)


def _exec_add_bel(ag: Agent, intention, im, frame, instr, at_end: bool = False, new_focus: bool = False) -> None:
    if type(instr.term) is not Literal:
        rule = resolve(instr.term, im.b)
        if isinstance(rule, PlanTerm) and rule.rule is not None:  # +R with R a rule term {h :- b}: Jason adds it
            ag.bb.add_rule(rule.rule.__class__(rule.rule.head, rule.rule.body, rule.rule.source_file,
                                               rule.rule.line), at_end=at_end)
            frame.pc += 1
            return
    lit = _belief_literal(instr.term, im.b)
    added = ag.bb.add(lit, at_end=at_end)
    frame.pc += 1
    if added is not None:
        plans = ag.plans
        if (not new_focus and not ag.event_waiters and not plans.has_update_sub_plans and plans._index is not None
                and not plans._var_plans and not plans._ns_plans
                and (ADD, BEL, added.neg, added.functor, len(added.args)) not in plans._index):
            return  # no plan for +b (PlanLibrary.relevant, inlined) and nobody waits: the event goes nowhere
        _post_belief_event(ag, Trigger(ADD, BEL, added), intention, new_focus)


def _exec_add_bel_end(ag, intention, im, frame, instr) -> None:
    _exec_add_bel(ag, intention, im, frame, instr, at_end=True)


def _exec_add_bel_new(ag, intention, im, frame, instr) -> None:
    _exec_add_bel(ag, intention, im, frame, instr, new_focus=True)


def _find_belief(ag: Agent, pattern: Literal, b: dict) -> Literal | None:
    """The first stored belief matching ``pattern`` (bindings made in ``b``)."""
    for fact in ag.bb.candidates(pattern, b):
        trail: list = []
        if unify(pattern.without_annots(), fact.without_annots(), b, trail):
            if pattern.annots:
                t2: list = []
                if not unify(pattern, fact, b, t2):
                    undo(b, t2, 0)
                    undo(b, trail, 0)
                    continue
            return fact
        undo(b, trail, 0)
    return None


def _exec_del_bel(ag: Agent, intention, im, frame, instr, new_focus: bool = False) -> None:
    pattern = resolve(instr.term, im.b)
    if type(pattern) is not Literal:
        raise IAError("wrong_arguments", f"'{to_str(pattern)}' is not a literal")
    if not has_source(pattern):
        pattern = pattern.add_annot(SOURCE_SELF)
    frame.pc += 1
    if is_ground(pattern):
        # the usual case: at most one stored belief has this plain part; it must carry every
        # annotation of the pattern (what the unification below checks, without a search)
        removed = ag.bb.remove(pattern, all_annots=True)
    else:
        found = _find_belief(ag, pattern, im.b)
        if found is None:
            return
        removed = ag.bb.remove(resolve(pattern, im.b))
    if removed is not None:
        _post_belief_event(ag, Trigger(DEL, BEL, removed), intention, new_focus)


def _exec_del_bel_new(ag, intention, im, frame, instr) -> None:
    _exec_del_bel(ag, intention, im, frame, instr, new_focus=True)


def _exec_upd_bel(ag: Agent, intention, im, frame, instr) -> None:
    """``-+b(args)``: remove the first ``b(_,..,_)[source(self)]`` (external -b event), add ``b(args)``."""
    lit = _belief_literal(instr.term, im.b)
    anon = Literal(lit.functor, tuple(Var("_") for _ in lit.args), (SOURCE_SELF,), lit.neg)
    b2: dict = {}
    found = _find_belief(ag, anon, b2)
    if found is not None:
        removed = ag.bb.remove(Literal(found.functor, found.args, (SOURCE_SELF,), found.neg))
        if removed is not None:
            ag.post_external(Trigger(DEL, BEL, removed))
    _exec_add_bel(ag, intention, im, frame, instr)


def _exec_action(ag: Agent, intention, im, frame, instr) -> None:
    action = resolve(instr.term, im.b)
    result = ag.arch.act(ag, action)
    if result is None:
        raise IAError("action_failed", f"no environment configured to execute the action {to_str(action)}")
    if isinstance(result, Future):
        def on_result(ctx, value) -> bool:
            ok, reason = _action_outcome(value)
            if not ok:
                # the bridge's reason (no_progress, timeout, ...) reaches -!g as reason(R)
                raise IAError("action_failed", f"action {to_str(action)} failed" + (f": {reason}" if reason else ""),
                              (Literal("reason", (Literal(reason),)),) if reason else ())
            return True
        ag.suspend_on(intention, im, Suspend(future=result, on_result=on_result, reason="action"), instr)
        return
    ok, reason = _action_outcome(result)
    if not ok:
        raise IAError("action_failed", f"action {to_str(action)} failed" + (f": {reason}" if reason else ""))
    frame.pc += 1


def _action_outcome(value) -> tuple[bool, str]:
    if isinstance(value, bool):
        return value, ""
    ok = getattr(value, "ok", None)
    if ok is not None:
        return bool(ok), getattr(value, "reason", "") or ""
    return bool(value), ""


def _exec_internal(ag: Agent, intention, im, frame, instr) -> None:
    lit = instr.term
    spec = ag.registry.actions.get(lit.functor) or ag.registry.get(lit.functor)
    if spec is None:
        raise IAError("ia_failed", f"unknown internal action {lit.functor}")
    b = im.b
    if lit.args:
        out = []
        for a in lit.args:  # resolve(a, b), without a call for variables bound to atoms or numbers
            ta = type(a)
            if ta is Var:
                v = b.get(a)
                if v is not None:
                    tv = type(v)
                    if tv is int or tv is float or tv is str or (tv is Literal and not v.args and v.annots is None
                                                                   and v.annot_tail is None):
                        out.append(v)
                        continue
            elif ta is int or ta is float or ta is str:
                out.append(a)
                continue
            elif ta is Literal and a.annots is None and a.annot_tail is None:
                if not a.args:
                    out.append(a)
                    continue
                # a structure of numbers, strings, atoms and variables bound to them (the usual
                # message content): resolve's result built here, without its calls
                sub = []
                for x in a.args:
                    tx = type(x)
                    if tx is Var:
                        x = b.get(x, x)
                        tx = type(x)
                    if tx is int or tx is float or tx is str or (tx is Literal and not x.args and x.annots is None
                                                                 and x.annot_tail is None):
                        sub.append(x)
                    else:
                        break
                else:
                    built = _new(Literal)  # Literal(a.functor, tuple(sub), None, a.neg), no class call
                    built.functor, built.args, built.annots = a.functor, tuple(sub), None
                    built.neg, built.annot_tail, built._hash = a.neg, None, None
                    out.append(built)
                    continue
            out.append(resolve(a, b))
        args = tuple(out)
    else:
        args = ()
    n = len(args)
    if n < spec.min_args or (spec.max_args is not None and n > spec.max_args):
        ag._check_arity(spec, lit, args)
    ctx = IAContext.__new__(IAContext)  # IAContext(ag, intention, im, b, []) without the class call
    ctx.agent, ctx.intention, ctx.im, ctx.b, ctx.trail = ag, intention, im, b, []
    result = spec.function(ctx, *args)
    if result is None or result is True:
        frame.pc += 1
        return
    if result is False:
        raise IAError("ia_failed", f"internal action {to_str(resolve(lit, b))} failed")
    if yields_solutions(result):
        for _ in result:
            frame.pc += 1
            return
        raise IAError("ia_failed", f"internal action {to_str(resolve(lit, b))} failed")
    if isinstance(result, Suspend):
        ag.suspend_on(intention, im, result, instr)
        return
    frame.pc += 1


def _exec_constraint(ag: Agent, intention, im, frame, instr) -> None:
    term = instr.term
    entry = _COMPILED.get(id(term))  # solve_first, inlined
    fn = entry[1] if entry is not None and entry[0] is term else compiled(term)
    if fn(ag, im.b, [], _true_k):
        frame.pc += 1
        return
    raise IAError("constraint_failed", f"constraint {to_str(resolve(instr.term, im.b))} is false")


def _exec_var(ag: Agent, intention, im, frame, instr) -> None:
    value = resolve(instr.term, im.b)
    if isinstance(value, PlanTerm) and value.body is not None:
        frame.pc += 1
        im.frames.append(Frame(value.body))
        return
    if isinstance(value, Literal):
        # a variable bound to a literal is executed as that formula
        klass = P.InternalAction if "." in value.functor else P.Action
        handler = _DISPATCH[klass]
        handler(ag, intention, im, frame, klass(value, instr.line))
        return
    raise IAError("wrong_arguments", f"'{to_str(value)}' cannot be executed as a formula")


def _loop_reset_vars(im: IntendedMeans, cond: Term, body: tuple) -> tuple:
    vs = variables(cond)
    P.body_variables(body, vs)
    return tuple(v for v in vs if v not in im.b)


def _exec_if(ag: Agent, intention, im, frame, instr) -> None:
    frame.pc += 1
    for cond, body in instr.branches:
        if solve_first(ag, cond, im.b):
            if body:
                im.frames.append(Frame(body))
            return
    if instr.else_body:
        im.frames.append(Frame(instr.else_body))


def _exec_while(ag: Agent, intention, im, frame, instr) -> None:
    frame.pc += 1
    reset = _loop_reset_vars(im, instr.cond, instr.body)
    if solve_first(ag, instr.cond, im.b):
        im.frames.append(Frame(instr.body, "while", instr, reset=reset))


def _exec_for(ag: Agent, intention, im, frame, instr) -> None:
    frame.pc += 1
    reset = _loop_reset_vars(im, instr.cond, instr.body)
    cond_vars = [v for v in variables(instr.cond) if v not in im.b]
    solutions = []
    b = im.b
    for _ in solve(ag, instr.cond, b):
        solutions.append({v: resolve(v, b) for v in cond_vars})
    for v in cond_vars:
        b.pop(v, None)
    if solutions:
        b.update(solutions[0])
        f = Frame(instr.body, "for", instr, solutions, reset=reset)
        f.index = 1
        im.frames.append(f)


def _exec_add_plan(ag: Agent, intention, im, frame, instr) -> None:
    term = resolve(instr.term, im.b)
    from agentspeak.stdlib.plans import add_plan_term
    add_plan_term(ag, term, SELF, at_end=instr.at_end)
    frame.pc += 1


def _exec_remove_plan(ag: Agent, intention, im, frame, instr) -> None:
    """``-{@l ...}`` is Jason's ``.remove_plan`` of the plan term: by its label. Without a label Jason
    fails the goal (a NullPointerException inside ``.remove_plan``); here with a message saying why."""
    term = resolve(instr.term, im.b)
    if isinstance(term, PlanTerm) and term.rule is not None:
        ag.bb.remove_rule(term.rule)
        frame.pc += 1
        return
    plan = term.as_plan() if isinstance(term, PlanTerm) else None
    if plan is None or plan.label is None:
        raise IAError("ia_failed", f"-{to_str(term) if not isinstance(term, PlanTerm) else term}: a plan is "
                                   f"removed by its label, and this plan term has none (write -{{@label ...}})")
    ag.plans.remove(plan.label)
    frame.pc += 1


def _exec_fork(ag: Agent, intention, im, frame, instr) -> None:
    from agentspeak.fork import start_fork
    start_fork(ag, intention, im, frame, instr)


def _exec_pycall(ag: Agent, intention, im, frame, instr) -> None:
    if instr.fn(IAContext(ag, intention, im, im.b, [])) is False:
        raise IAError("ia_failed", f"{instr} failed")
    frame.pc += 1


def _exec_trigger(ag: Agent, intention, im, frame, instr) -> None:
    raise IAError("wrong_arguments", f"a trigger ({instr}) is not a body formula")


_DISPATCH: dict = {
    P.Achieve: _exec_achieve, P.AchieveNew: _exec_achieve_new, P.Test: _exec_test,
    P.AddBel: _exec_add_bel, P.AddBelEnd: _exec_add_bel_end, P.AddBelNew: _exec_add_bel_new,
    P.DelBel: _exec_del_bel, P.DelBelNew: _exec_del_bel_new, P.UpdBel: _exec_upd_bel,
    P.Action: _exec_action, P.InternalAction: _exec_internal, P.Constraint: _exec_constraint,
    P.ExecVar: _exec_var, P.If: _exec_if, P.While: _exec_while, P.For: _exec_for,
    P.AddPlan: _exec_add_plan, P.RemovePlan: _exec_remove_plan, P.Fork: _exec_fork,
    P.TriggerInstr: _exec_trigger, P.PyCall: _exec_pycall,
}
