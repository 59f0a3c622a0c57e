"""The MAS and the agent's own state seen from a program: create_agent, kill_agent, list_files, at, type,
intention. Each follows Jason 3.3's class of the same name in ``jason/stdlib``."""
from __future__ import annotations

import itertools
import os
import re

from agentspeak.program import ACHIEVE, ADD, PlanTerm, Plan, Trigger, body_variables, substitute
from agentspeak.stdlib.registry import IAError, Suspend, internal_action, wrong_arguments
from agentspeak.beliefs import SOURCE_SELF
from agentspeak.directory import service_text
from agentspeak.terms import (
    LOCAL_NS_PREFIX, NIL, Literal, Var, is_list, list_items, make_list, resolve, to_print_str, to_str,
)
from agentspeak.unify import undo, unifies


def _text(t) -> str:
    return t if isinstance(t, str) else to_print_str(t)


@internal_action(".create_agent", args=(2, 3))
def create_agent(ctx, name, source, options=None):
    """``.create_agent(Name, "file.asl"[, Options])``: start a new agent of this MAS with that source (found
    beside the working directory or along the project's source path). A variable Name gets the name."""
    agent = ctx.agent
    create = getattr(agent.arch, "create_agent", None)
    if create is None:
        raise IAError("ia_failed", f"the architecture of {agent.name} cannot create agents")
    if isinstance(name, Var):
        wanted = name.name[:1].lower() + name.name[1:]
    else:
        wanted = _text(name)
    if not isinstance(source, str):
        raise wrong_arguments(".create_agent: the source is a string (a file name)")
    created = create(agent, wanted, source)
    return ctx.unify(name, created) if isinstance(name, Var) else True


@internal_action(".clone", args=1)
def clone(ctx, name):
    """``.clone(Name)``: a new agent of this MAS with a copy of this agent's beliefs, rules and plans
    (Jason's: no goals, events or intentions are copied)."""
    make = getattr(ctx.agent.arch, "clone_agent", None)
    if make is None:
        raise IAError("ia_failed", f"the architecture of {ctx.agent.name} cannot clone agents")
    make(ctx.agent, _text(name))
    return True


@internal_action(".kill_agent", args=(1, 2))
def kill_agent(ctx, name, deadline=0):
    """``.kill_agent(Name[, Deadline])``: stop and remove an agent of this MAS (fails if there is none of that
    name). With a deadline (ms), as Jason's, the agent first gets ``+jag_shutting_down(Deadline)`` and runs
    until then (its own clock: simulated time under a simulator, as ``.wait``)."""
    if isinstance(deadline, bool) or not isinstance(deadline, (int, float)) or deadline < 0:
        raise wrong_arguments(".kill_agent: the deadline is a number of milliseconds, 0 or more")
    kill = getattr(ctx.agent.arch, "kill_agent", None)
    if kill is None:
        raise IAError("ia_failed", f"the architecture of {ctx.agent.name} cannot kill agents")
    return bool(kill(ctx.agent, _text(name), deadline / 1000.0))


@internal_action(".list_files", args=(2, 3))
def list_files(ctx, folder, pattern_or_result, result=None):
    """``.list_files(Folder[, Regex], Files)``: the files under Folder (recursively) whose name matches
    Regex (the whole name, as Java's ``String.matches``), as paths that start with Folder."""
    if result is None:
        pattern, result = ".*", pattern_or_result
    else:
        pattern = pattern_or_result
    if not isinstance(folder, str) or not isinstance(pattern, str):
        raise wrong_arguments(".list_files: the folder and the pattern are strings")
    try:
        regex = re.compile(pattern)
    except re.error as exc:
        raise wrong_arguments(f".list_files: bad pattern {pattern!r}: {exc}") from None
    found: list[str] = []

    def walk(d: str) -> None:
        try:
            entries = sorted(os.listdir(d))
        except OSError:
            return
        for e in entries:
            path = os.path.join(d, e)
            if os.path.isfile(path) and regex.fullmatch(e):
                found.append(path)
            if os.path.isdir(path):
                walk(path)

    walk(folder)
    return ctx.unify(result, make_list(found))


_UNITS = {"ms": 0.001, "s": 1, "second": 1, "m": 60, "minute": 60, "h": 3600, "hour": 3600, "d": 86400, "day": 86400}


def _at_seconds(when: str) -> float:
    m = re.fullmatch(r"\s*now\s*\+\s*(\d+)\s*([a-z]*)\s*", when)
    if m is None:
        raise wrong_arguments(f".at: cannot read the time {when!r} (write \"now +3 s\")")
    unit = m.group(2)
    if not unit:
        return int(m.group(1)) / 1000.0
    for name, factor in _UNITS.items():
        if unit == name or (len(name) > 2 and unit.startswith(name)):
            return int(m.group(1)) * factor
    raise wrong_arguments(f".at: unknown time unit {unit!r} (ms, s, m, h or d)")


@internal_action(".at", args=2)
def at(ctx, when, event):
    """``.at("now +2 s", {+!g})``: post the event (a new intention) at that time."""
    if not isinstance(when, str):
        raise wrong_arguments(".at: the time is a string such as \"now +2 s\"")
    trigger = event.as_trigger() if isinstance(event, PlanTerm) else None
    if trigger is None:
        raise wrong_arguments(".at: the event is a trigger term such as {+!g}")
    agent = ctx.agent
    literal = resolve(trigger.literal, ctx.b)
    if trigger.kind == ACHIEVE and trigger.op == ADD and isinstance(literal, Literal):
        from agentspeak.body import fresh_goal   # the body formulas import the internal actions
        literal = fresh_goal(literal, {})
    pending = _AtEvent(agent, Trigger(trigger.op, trigger.kind, literal))
    ats = getattr(agent, "at_events", None)
    if ats is None:
        ats = agent.at_events = set()
    ats.add(pending)
    agent.add_timer(_at_seconds(when), pending)


class _AtEvent:
    """An event ``.at`` posts when its time comes, unless cancelled first (``.drop_all_intentions`` sets
    ``cancelled`` on each of ``agent.at_events``: Jason's ``at.cancelAts``)."""
    __slots__ = ("agent", "trigger", "cancelled")

    def __init__(self, agent, trigger: Trigger) -> None:
        self.agent, self.trigger, self.cancelled = agent, trigger, False

    def __call__(self) -> None:
        self.agent.at_events.discard(self)
        if not self.cancelled:
            self.agent.post_external(self.trigger, force=True)



def _types(x) -> list[str]:
    from agentspeak.terms import Cons, NIL, is_ground
    out = []
    tx = type(x)
    if (tx is int or tx is float) and tx is not bool:
        out.append("number")
    if tx is Literal and not x.args and not x.neg and x.annots is None and x.annot_tail is None:
        out.append("atom")
    if tx is Literal:
        out.append("literal")
    if tx is str:
        out.append("string")
    if tx is Cons or x is NIL:
        out.append("list")
    if tx is Literal and x.args or tx is Cons:
        out.append("structure")
    if tx is PlanTerm:
        out.append("plan")
    if not isinstance(x, Var) and is_ground(x):
        out.append("ground")
    if isinstance(x, Var):
        out.append("free")
    return out


@internal_action(".save_agent", args=(1, 2))
def save_agent(ctx, file, goals=None):
    """``.save_agent(File[, Goals])``: write the agent's beliefs (without ``source(self)``), rules,
    the given initial goals and its plans as an AgentSpeak file (Jason's layout), relative to the
    working directory; a file that cannot be written fails the formula with the reason."""
    agent = ctx.agent
    name = file if isinstance(file, str) else to_print_str(file)
    if goals is not None and not is_list(goals):
        raise wrong_arguments(".save_agent: the initial goals are a list")
    lines = ["// beliefs and rules"]
    for lit in agent.bb.literals():
        annots = tuple(a for a in lit.annots or () if a != SOURCE_SELF) or None
        lines.append(to_str(Literal(lit.functor, lit.args, annots, lit.neg)) + ".")
    lines.extend(str(r) + "." for r in agent.bb.rules())
    lines += ["", "", "// initial goals"]
    lines.extend("!" + to_str(g) + "." for g in list_items(goals or NIL))
    lines += ["", "", "// plans"]
    lines.extend(p.source_text() for p in agent.plans)
    try:
        with open(name, "w", encoding="utf-8") as out:
            out.write("\n".join(lines) + "\n")
    except OSError as exc:
        raise IAError("ia_failed", f".save_agent: cannot write {name}: {exc.strerror or exc}") from None
    return True


@internal_action(".get_src_info", args=2)
def get_src_info(ctx, term, result):
    """``.get_src_info(T, L)``: L is the literal T with ``code_src`` and ``code_line`` annotations (Jason's
    test library reports where an assertion is). Terms here carry no source position, so it is the
    position of this formula, which is where T was written when it is written in the call."""
    if not isinstance(term, Literal):
        return False
    from agentspeak.agent import source_url
    im = ctx.im
    instr = im.current() if im is not None else None
    lit = term
    if not any(isinstance(a, Literal) and a.functor == "code_src" for a in lit.annots or ()):
        src = source_url(im.plan.source_file) if im is not None else "nocode"
        lit = lit.add_annot(Literal("code_src", (src,)))
    if not any(isinstance(a, Literal) and a.functor == "code_line" for a in lit.annots or ()):
        lit = lit.add_annot(Literal("code_line", (getattr(instr, "line", 0) or (im.plan.line if im else 0),)))
    return ctx.unify(result, lit)


@internal_action(".type", args=2)
def type_(ctx, x, kind):
    """``.type(X, T)``: T is each of number, atom, literal, string, list, structure, plan, ground, free
    that X is (Jason's order, from the most primitive); with T given, whether X is of that type."""
    for name in _types(x):
        mark = len(ctx.trail)
        if ctx.unify(kind, Literal(name)):
            yield
        undo(ctx.b, ctx.trail, mark)


# ---------------------------------------------------------------------- intentions as terms
def _label_term(plan: Plan) -> Literal:
    label = plan.ensure_label()
    lit = label if isinstance(label, Literal) else Literal("l")
    from agentspeak.agent import source_url
    for annot in (Literal("code_line", (plan.line,)), Literal("code_src", (source_url(plan.source_file),))):
        if not lit.annots or not any(isinstance(a, Literal) and a.functor == annot.functor for a in lit.annots):
            lit = lit.add_annot(annot)
    return lit


_anonymous_ids = itertools.count(1)


def _remaining_body(im) -> tuple:
    out: list = []
    for frame in reversed(im.frames):
        out.extend(frame.body[frame.pc:])
    return tuple(out)


def im_term(im) -> Literal:
    """``im(Label, {Trigger}, {Body still to run}, [map(Var, Value), ...])`` (Jason's IntendedMeans
    as a term); the trigger with the intended means' bindings applied, the body with fresh variables."""
    from agentspeak.terms import rename
    b = im.b
    fresh: dict = {}  # the term shares no variable with the running plan (Jason makes them anonymous)

    def copy(t):
        return rename(substitute(t, b), fresh)
    trig = im.plan.trigger
    literal = im.event_literal if im.event_literal is not None else trig.literal
    trigger = PlanTerm(plan=Plan(Trigger(trig.op, trig.kind, copy(literal))))
    remaining = _remaining_body(im)
    # the body as written, its variables made anonymous (Jason's IntendedMeans.getAsTerm: not the values;
    # Jason's test manager counts each assert by this term, so two asserts of equal values stay two)
    for v in body_variables(remaining):
        if v not in fresh:  # Jason's UnnamedVar: `_<id><name>`, a name of its own (terms compare by text)
            fresh[v] = Var(f"_{next(_anonymous_ids)}{'' if v.name.startswith('_') else v.name}")
    body = PlanTerm(body=tuple(instr.map_terms(lambda t: rename(t, fresh)) if hasattr(instr, "map_terms") else instr
                               for instr in remaining))
    # the bindings of the variables the rest of the plan still uses (Jason lists the whole unifier; the
    # values of variables the plan is done with can be large, e.g. a list of plans, and copying them
    # for every assert made Jason's test harness slow)
    unifier = make_list([Literal("map", (Var(v.name), copy(v))) for v in body_variables(remaining)
                         if v in b and not v.name.startswith("_")])
    return Literal("im", (_label_term(im.plan), trigger, body, unifier))


def intention_state(agent, intention) -> Literal:
    if intention is getattr(agent, "current_intention", None) or not intention.suspended:
        return Literal("running")
    return Literal("waiting", (), (Literal("reason", (Literal(str(intention.suspended)),)),))


@internal_action(".intention", args=(2, 4))
def intention(ctx, ident, state, stack=None, which=None):
    """``.intention(Id, State[, Stack[, current]])``: the agent's intentions (each intended means as
    ``im(Label, {Trigger}, {Body}, Unifier)``, the top first); ``current`` selects the intention running
    this formula (in a plan context: the intention whose event is being handled)."""
    agent = ctx.agent
    current = ctx.intention if ctx.intention is not None else getattr(agent, "current_intention", None)
    if isinstance(which, Literal) and which.functor == "current":
        candidates = [current] if current is not None else []
    else:
        candidates = list(agent.intentions())
        if current is not None and current not in candidates:
            candidates.append(current)
    for i in candidates:
        mark = len(ctx.trail)
        st = Literal("running") if i is current else intention_state(agent, i)
        if ctx.unify(ident, i.id) and ctx.unify(state, st) and (
                stack is None or ctx.unify(stack, make_list([im_term(im) for im in reversed(i.stack)]))):
            yield
        undo(ctx.b, ctx.trail, mark)


@internal_action(".current_intention", args=1)
def current_intention(ctx, result):
    """``.current_intention(intention(Id, Stack))`` (Jason keeps it beside ``.intention``)."""
    i = ctx.intention if ctx.intention is not None else getattr(ctx.agent, "current_intention", None)
    if i is None:
        return False
    return ctx.unify(result, Literal("intention", (i.id, make_list([im_term(im) for im in reversed(i.stack)]))))


@internal_action(".eval", args=2)
def eval_(ctx, result, formula):
    """``.eval(X, Formula)``: X is ``true`` if the logical formula holds, else ``false``."""
    from agentspeak.solver import solve_first
    b = dict(ctx.b)
    return ctx.unify(result, Literal("true" if solve_first(ctx.agent, formula, b) else "false"))


@internal_action(".relevant_rules", args=2)
def relevant_rules(ctx, pattern, result):
    """``.relevant_rules(p(_,_), L)``: the rules whose head unifies with the pattern, as rule terms."""
    from agentspeak.unify import unifies
    if isinstance(pattern, Var):  # every rule
        rules = list(ctx.agent.bb.rules())
    elif isinstance(pattern, Literal):
        rules = [r for r in ctx.agent.bb.rules_for(pattern) if unifies(pattern, r.head, {})]
    else:
        raise wrong_arguments(".relevant_rules needs a literal")
    return ctx.unify(result, make_list([PlanTerm(rule=r).rename({}) for r in rules]))


@internal_action(".list_rules", args=(0, 1))
def list_rules(ctx, pattern=None):
    """Print the rules (those whose head unifies with the pattern)."""
    from agentspeak.unify import unifies
    for r in ctx.agent.bb.rules():
        if pattern is None or (isinstance(pattern, Literal) and unifies(pattern, r.head, {})):
            ctx.agent.arch.print_line(ctx.agent, str(r) + ".")


@internal_action(".drop_event", args=1)
def drop_event(ctx, goal):
    """``.drop_event(G)``: remove the pending ``+!G`` events (the goals not yet intended)."""
    from agentspeak.unify import unifies
    agent = ctx.agent
    keep = [ev for ev in agent.events
            if not (ev.trigger.op == ADD and ev.trigger.kind == ACHIEVE and ev.intention is None
                    and unifies(goal, ev.trigger.literal, {}))]
    agent.events.clear()
    agent.events.extend(keep)


# ---------------------------------------------------------------------- name spaces
def _namespaces(agent) -> list[str]:
    """The agent's name spaces: those of its beliefs and rules, ``default``, and ``kqml`` (Jason's
    ``kqmlPlans.asl`` keeps its rules there; here they are Python, the name space is listed as Jason lists it)."""
    return ["kqml"] + [ns for ns in agent.bb.namespaces() if ns != "kqml"]


@internal_action(".namespace", args=1)
def namespace(ctx, ns):
    """``.namespace(NS)``: NS is a name space of the agent (backtracks over them when NS is free)."""
    if not isinstance(ns, Var) and not (isinstance(ns, Literal) and not ns.args):
        raise wrong_arguments(".namespace: the argument must be an atom or a variable")
    for name in _namespaces(ctx.agent):
        if name.startswith(LOCAL_NS_PREFIX) and isinstance(ns, Var):
            continue  # a variable never takes a local name space (Jason's Unifier.bind): it stays private
        mark = len(ctx.trail)
        if ctx.unify(ns, Literal(name)):
            yield
        undo(ctx.b, ctx.trail, mark)


@internal_action(".namespace_set_prop", args=3)
def namespace_set_prop(ctx, ns, key, value):
    """``.namespace_set_prop(NS, Key, Value)``: a property of a name space."""
    props = ctx.agent.__dict__.setdefault("namespace_props", {})
    props.setdefault(_text(ns), {})[key] = value


@internal_action(".namespace_get_prop", args=(2, 4))
def namespace_get_prop(ctx, ns, key, value=None, default=None):
    """``.namespace_get_prop(NS, Key[, Value[, Default]])``: backtracks over the keys when Key is free."""
    props = getattr(ctx.agent, "namespace_props", {}).get(_text(ns), {})
    if not isinstance(key, Var) and key not in props:
        if default is not None and value is not None:
            if ctx.unify(value, default):
                yield
        return
    for k, v in list(props.items()):
        mark = len(ctx.trail)
        if ctx.unify(key, k) and (value is None or ctx.unify(value, v)):
            yield
        undo(ctx.b, ctx.trail, mark)


@internal_action(".add_nested_source", args=3)
def add_nested_source(ctx, lit, source, result):
    """``.add_nested_source(p[a], bob, R)``: R is ``p[source(bob)[a]]`` (a list: each of its literals)."""
    from agentspeak.communication import nested_source
    from agentspeak.terms import Cons, NIL, list_items
    if isinstance(lit, Cons) or lit is NIL:
        return ctx.unify(result, make_list([nested_source(x, source) if isinstance(x, Literal) else x
                                            for x in list_items(lit)]))
    if not isinstance(lit, Literal):
        raise wrong_arguments(".add_nested_source needs a literal")
    return ctx.unify(result, nested_source(lit, source))


# ---------------------------------------------------------------------- directory facilitator
# Jason's jason.stdlib.df_*: the semantics are agentspeak.directory's; the architecture gives the directory
# of the MAS (the in-process one, or the one that reaches the agents of other processes: agents.directory).
def _directory(ctx):
    find = getattr(ctx.agent.arch, "directory", None)
    if find is None:
        raise IAError("ia_failed", f"the architecture of {ctx.agent.name} has no directory facilitator")
    return find(ctx.agent)


@internal_action(".df_register", args=(1, 2))
def df_register(ctx, service, kind=None):
    """``.df_register(S[, Type])``: this agent provides service S (the type is ignored, as in Jason's
    local infrastructure); subscribers of S are told ``provider(Ag, "S")``."""
    _directory(ctx).register(ctx.agent.name, service_text(service))


@internal_action(".df_deregister", args=(1, 2))
def df_deregister(ctx, service, kind=None):
    """``.df_deregister(S[, Type])``: this agent no longer provides S."""
    _directory(ctx).deregister(ctx.agent.name, service_text(service))


@internal_action(".df_search", args=(2, 3))
def df_search(ctx, service, kind_or_result, result=None):
    """``.df_search(S[, Type], L)``: L is the list of the agents providing S, in any process of the MAS."""
    result = kind_or_result if result is None else result
    return ctx.unify(result, make_list([Literal(p) for p in _directory(ctx).search(service_text(service))]))


@internal_action(".df_subscribe", args=(1, 2))
def df_subscribe(ctx, service, kind=None):
    """``.df_subscribe(S[, Type])``: be told ``provider(Ag, "S")`` (from ``df``) for each provider of S,
    now and whenever one registers."""
    _directory(ctx).subscribe(ctx.agent.name, service_text(service))


# ---------------------------------------------------------------------- small terms and lists
@internal_action(".copy_term", args=2)
def copy_term(ctx, term, result):
    """``.copy_term(T, C)``: C is T with fresh variables."""
    from agentspeak.terms import rename
    return ctx.unify(result, rename(term, {}))


@internal_action(".rename_apart", args=2)
def rename_apart(ctx, term, result):
    """``.rename_apart(b(X,Y,a), R)``: R is ``b(_X,_Y,a)`` with variables no one else holds."""
    from agentspeak.terms import rename
    return ctx.unify(result, rename(term, {}))


@internal_action(".remove_source_annot", args=2)
def remove_source_annot(ctx, lit, result):
    """``.remove_source_annot(p[source(a),x], R)``: R is ``p[x]``."""
    if not isinstance(lit, Literal):
        raise wrong_arguments(".remove_source_annot needs a literal")
    kept = tuple(a for a in lit.annots or () if not (isinstance(a, Literal) and a.functor == "source"))
    return ctx.unify(result, Literal(lit.functor, lit.args, kept or None, lit.neg, lit.annot_tail))


def _seq(t, action: str):
    from agentspeak.terms import list_items
    if isinstance(t, str):
        return t
    try:
        return list_items(t)
    except TypeError:
        raise wrong_arguments(f"{action}: '{t}' is neither a list nor a string") from None


def _as_term(part, like):
    return part if isinstance(like, str) else make_list(part)


def _each_part(ctx, pattern, parts, like):
    for part in parts:
        mark = len(ctx.trail)
        if ctx.unify(pattern, _as_term(part, like)):
            yield
        undo(ctx.b, ctx.trail, mark)


@internal_action(".prefix", args=2)
def prefix(ctx, pre, whole):
    """``.prefix(P, L)``: P is a prefix of list or string L (backtracks, shortest first)."""
    seq = _seq(whole, ".prefix")
    return _each_part(ctx, pre, [seq[:i] for i in range(len(seq) + 1)], whole)


@internal_action(".suffix", args=2)
def suffix(ctx, suf, whole):
    """``.suffix(S, L)``: S is a suffix of L (backtracks, longest first)."""
    seq = _seq(whole, ".suffix")
    return _each_part(ctx, suf, [seq[i:] for i in range(len(seq) + 1)], whole)


@internal_action(".sublist", args=2)
def sublist(ctx, sub, whole):
    """``.sublist(S, L)``: S is a contiguous part of L (prefixes of each suffix, as Jason)."""
    seq = _seq(whole, ".sublist")
    parts = [seq[i:][:j] for i in range(len(seq) + 1) for j in range(len(seq) - i, -1, -1)]
    return _each_part(ctx, sub, parts, whole)


@internal_action(".relevant_plan", args=2)
def relevant_plan(ctx, trigger_term, plan):
    """``.relevant_plan({+!g}, P)``: backtracks over the plans relevant for the trigger (fresh copies)."""
    from agentspeak.unify import unifies
    trigger = trigger_term.as_trigger() if isinstance(trigger_term, PlanTerm) else None
    if trigger is None:
        raise wrong_arguments(".relevant_plan needs a trigger term such as {+!g}")
    found = [PlanTerm(plan=p).rename({}) for p in ctx.agent.plans.relevant(trigger)
             if p.trigger.op == trigger.op and p.trigger.kind == trigger.kind
             and unifies(p.trigger.literal, trigger.literal, {})]
    return _each(ctx, plan, found)


def _each(ctx, pattern, values):
    for v in values:
        mark = len(ctx.trail)
        if ctx.unify(pattern, v):
            yield
        undo(ctx.b, ctx.trail, mark)


@internal_action(".signal", args=1)
def signal(ctx, event):
    """``.signal({+t})``, ``.signal({+!g})``: post that event (a new intention handles it)."""
    trigger = event.as_trigger() if isinstance(event, PlanTerm) else None
    if trigger is None:
        raise wrong_arguments(".signal needs an event such as {+b} or {+!g}")
    ctx.agent.post_external(Trigger(trigger.op, trigger.kind, ctx.resolve(trigger.literal)), force=True)


@internal_action(".done", args=(0, 1))
def done(ctx, goal=None):
    """Jason(ER)'s ``.done`` / ``.done(G)``: the goal is achieved. Without G, the goal of the running
    plan; in a sub-plan run for a belief update (a branch), the goal whose sub-plan it is, and the
    branch ends. Only the calling intention (and the one it branched from) is affected."""
    from agentspeak.stdlib.bdi import finish_at
    agent, current = ctx.agent, ctx.intention
    owner = current.branch[0] if current.branch is not None else current
    if goal is None:
        target = current.branch[1] if current.branch is not None else current.stack[-1]
        idx = next((k for k, im in enumerate(owner.stack) if im is target), None)
    else:
        idx = next((k for k in range(len(owner.stack) - 1, -1, -1)
                    if owner.stack[k].plan.trigger.kind == ACHIEVE
                    and unifies(goal, resolve(owner.stack[k].event_literal, owner.stack[k].b), {})), None)
    if current.branch is not None:
        agent.drop_intention(current)
        if idx is not None and not owner.dropped:
            finish_at(agent, owner, idx, None)
        return Suspend(reason="finished")
    for other in agent.intentions():  # the branches of this intention stop with it (as Jason's)
        if other.branch is not None and other.branch[0] is current:
            agent.drop_intention(other)
    if idx is not None:
        finish_at(agent, current, idx, current)
    if current.dropped:
        return Suspend(reason="finished")
    return True


@internal_action(".drop_future_intention", args=1)
def drop_future_intention(ctx, goal):
    """``.drop_future_intention(G)``: drop the intentions that will pursue G (no event is produced)."""
    from agentspeak.stdlib.bdi import drop_intention
    return drop_intention(ctx, goal)


@internal_action(".perceive", args=0)
def perceive(ctx):
    """Perceive now (here every reasoning cycle perceives already)."""


@internal_action(".verbose", args=1)
def verbose(ctx, level):
    """``.verbose(0|1|2)``: how much the interpreter logs (Jason's verbose setting)."""
    import logging
    logging.getLogger("faultmas.agentspeak").setLevel(
        {0: logging.ERROR, 1: logging.WARNING, 2: logging.DEBUG}.get(level if isinstance(level, int) else 1))


@internal_action(".version", args=1)
def version(ctx, result):
    """``.version(V)``: the Jason version whose language this interpreter follows."""
    return ctx.unify(result, "3.3.2 (faultmas)")


@internal_action(".puts", args=(1, 2))
def puts(ctx, text, result=None):
    """``.puts("X is #{X}")``: print the text with each ``#{Term}`` replaced by the term with the
    intention's bindings (or unify it with a second argument)."""
    import re as _re
    if not isinstance(text, str):
        raise wrong_arguments(".puts needs a string")
    from agentspeak.parser import parse_term
    from agentspeak.terms import to_print_str, resolve

    def value(m):
        term = parse_term(m.group(1))
        names = {v.name: v for v in ctx.b if isinstance(v, Var)}
        from agentspeak.terms import rename
        mapping = {}
        term = rename(term, mapping)
        for old, new in mapping.items():
            if old.name in names:
                ctx.b.setdefault(new, names[old.name])
        return to_print_str(resolve(term, ctx.b))
    out = _re.sub(r"#\{([^}]*)\}", value, text)
    if result is not None:
        return ctx.unify(result, out)
    ctx.agent.arch.print_line(ctx.agent, out)


@internal_action(".print_unifier", args=0)
def print_unifier(ctx):
    """Print the bindings of the running plan's named variables."""
    from agentspeak.terms import resolve, to_str as _to_str
    pairs = [f"{v.name}={_to_str(resolve(v, ctx.b))}" for v in ctx.b if isinstance(v, Var) and not v.name.startswith("_")]
    ctx.agent.arch.print_line(ctx.agent, "{" + ", ".join(pairs) + "}")
