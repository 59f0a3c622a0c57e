"""What a parsed agent program is made of: triggers, plans, rules, body instructions, plan terms.

These are plain data, built by ``agentspeak.parser`` and run by ``agentspeak.agent``. Every body
instruction keeps the source line it came from so failures can say ``code_line``.
"""
from __future__ import annotations

from typing import Callable

from agentspeak.terms import (
    MAX_TERM_DEPTH, NIL, And, Arith, Bindings, Cons, Func, Literal, Not, Or, Rel, Term, Var, rename, resolve,
    term_height, to_str, variables,
)

# trigger operators and types, as Jason names them
ADD, DEL, META = "+", "-", "^"
BEL, ACHIEVE, TEST = "", "!", "?"


class Trigger:
    """``+b``, ``-b``, ``+!g``, ``-!g``, ``+?g``, ``-?g``, ``^!g``. Also built without ``__init__`` when a
    message arrives (see ``agentspeak.agent._new``)."""

    __slots__ = ("op", "kind", "literal")

    def __init__(self, op: str, kind: str, literal: Term) -> None:
        self.op, self.kind, self.literal = op, kind, literal

    @property
    def key(self) -> tuple:
        """Index key in the plan library: (op, kind, negated, functor, arity), or None for a variable."""
        lit = self.literal
        if isinstance(lit, Literal):
            return (self.op, self.kind, lit.neg, lit.functor, len(lit.args))
        return None

    def is_goal(self) -> bool:
        return self.kind != BEL

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Trigger) and self.op == other.op and self.kind == other.kind
                and self.literal == other.literal)

    def __hash__(self) -> int:
        return hash((self.op, self.kind, self.literal))

    def resolve(self, b: Bindings, depth: int = 0) -> "Trigger":
        return Trigger(self.op, self.kind, resolve(self.literal, b, depth + 1))

    def rename(self, mapping: dict) -> "Trigger":
        return Trigger(self.op, self.kind, rename(self.literal, mapping))

    def subterms(self) -> list:
        return [self.literal]

    def unify_with(self, other: object, b: Bindings, trail: list) -> bool:
        from agentspeak.unify import unify
        return (isinstance(other, Trigger) and self.op == other.op and self.kind == other.kind
                and unify(self.literal, other.literal, b, trail))

    def __str__(self) -> str:
        return f"{self.op}{self.kind}{to_str(self.literal)}"

    __repr__ = __str__


# -- body instructions ----------------------------------------------------------------------
class Instr:
    """A body formula. ``line`` is its source line (for error annotations)."""

    __slots__ = ("line",)
    text_prefix = ""

    def terms(self) -> list:
        return []

    def map_terms(self, f: Callable[[Term], Term]) -> "Instr":
        raise NotImplementedError

    def __str__(self) -> str:
        return self.text_prefix + ",".join(to_str(t) for t in self.terms())

    __repr__ = __str__


class _OneTerm(Instr):
    __slots__ = ("term",)

    def __init__(self, term: Term, line: int = 0) -> None:
        self.term = term
        self.line = line

    def terms(self) -> list:
        return [self.term]

    def map_terms(self, f):
        return type(self)(f(self.term), self.line)

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and self.term == other.term

    def __hash__(self) -> int:
        return hash((type(self).__name__, self.term))


class Achieve(_OneTerm):
    """``!g`` (same intention)."""
    __slots__ = ()
    text_prefix = "!"


class AchieveNew(_OneTerm):
    """``!!g`` (a new intention; the current plan goes on at once)."""
    __slots__ = ()
    text_prefix = "!!"


class Test(_OneTerm):
    """``?q``: the belief base first, then ``+?q`` plans."""
    __slots__ = ()
    text_prefix = "?"


class AddBel(_OneTerm):
    """``+b`` / ``+<b`` (at the start of the belief base)."""
    __slots__ = ()
    text_prefix = "+"


class AddBelEnd(_OneTerm):
    """``+>b`` (at the end)."""
    __slots__ = ()
    text_prefix = "+>"


class AddBelNew(_OneTerm):
    """``++b`` (the +b event starts a new intention)."""
    __slots__ = ()
    text_prefix = "++"


class DelBel(_OneTerm):
    __slots__ = ()
    text_prefix = "-"


class DelBelNew(_OneTerm):
    __slots__ = ()
    text_prefix = "--"


class UpdBel(_OneTerm):
    """``-+b``: remove the first ``b(_,...)`` then add ``b(...)``."""
    __slots__ = ()
    text_prefix = "-+"


class Action(_OneTerm):
    """An environment action (executed by the agent architecture's ``act``)."""
    __slots__ = ()


class InternalAction(_OneTerm):
    """``.name(args)`` or ``lib.name(args)``."""
    __slots__ = ()


class Constraint(_OneTerm):
    """A relational or logical formula executed as a test (``X = Y + 1``, ``X > 3``)."""
    __slots__ = ()


class ExecVar(_OneTerm):
    """A variable bound to a plan body, executed in place."""
    __slots__ = ()


class AddPlan(Instr):
    """``+{plan}`` / ``+>{plan}``."""
    __slots__ = ("term", "at_end")

    def __init__(self, term: Term, at_end: bool = False, line: int = 0) -> None:
        self.term, self.at_end, self.line = term, at_end, line

    def terms(self) -> list:
        return [self.term]

    def map_terms(self, f):
        return AddPlan(f(self.term), self.at_end, self.line)

    def __str__(self) -> str:
        return ("+>" if self.at_end else "+") + to_str(self.term)


class RemovePlan(_OneTerm):
    __slots__ = ()
    text_prefix = "-"


class If(Instr):
    """``if (c) {..} elif (c) {..} else {..}``: branches is a tuple of (condition, body)."""
    __slots__ = ("branches", "else_body")

    def __init__(self, branches: tuple, else_body: tuple | None, line: int = 0) -> None:
        self.branches, self.else_body, self.line = branches, else_body, line

    def terms(self) -> list:
        return [c for c, _ in self.branches]

    def map_terms(self, f):
        return If(tuple((f(c), map_body(b, f)) for c, b in self.branches),
                  map_body(self.else_body, f) if self.else_body is not None else None, self.line)

    def __str__(self) -> str:
        parts = []
        for i, (c, b) in enumerate(self.branches):
            parts.append(("if" if i == 0 else " elif") + f" ({to_str(c)}) {{ {body_str(b)} }}")
        if self.else_body is not None:
            parts.append(f" else {{ {body_str(self.else_body)} }}")
        return "".join(parts)


class While(Instr):
    __slots__ = ("cond", "body")

    def __init__(self, cond: Term, body: tuple, line: int = 0) -> None:
        self.cond, self.body, self.line = cond, body, line

    def terms(self) -> list:
        return [self.cond]

    def map_terms(self, f):
        return While(f(self.cond), map_body(self.body, f), self.line)

    def __str__(self) -> str:
        return f"while ({to_str(self.cond)}) {{ {body_str(self.body)} }}"


class For(Instr):
    __slots__ = ("cond", "body")

    def __init__(self, cond: Term, body: tuple, line: int = 0) -> None:
        self.cond, self.body, self.line = cond, body, line

    def terms(self) -> list:
        return [self.cond]

    def map_terms(self, f):
        return For(f(self.cond), map_body(self.body, f), self.line)

    def __str__(self) -> str:
        return f"for ({to_str(self.cond)}) {{ {body_str(self.body)} }}"


class Fork(Instr):
    """``A |&| B`` (join: wait for all, kind "and") or ``A ||| B`` (wait for one, kind "or")."""
    __slots__ = ("kind", "branches")

    def __init__(self, kind: str, branches: tuple, line: int = 0) -> None:
        self.kind, self.branches, self.line = kind, branches, line

    def map_terms(self, f):
        return Fork(self.kind, tuple(map_body(b, f) for b in self.branches), self.line)

    def __str__(self) -> str:
        sep = " |&| " if self.kind == "and" else " ||| "
        return sep.join(body_str(b) for b in self.branches)


def map_body(body: tuple, f: Callable[[Term], Term]) -> tuple:
    return tuple(i.map_terms(f) for i in body)


def body_str(body: tuple) -> str:
    return "; ".join(str(i) for i in body)


def body_terms(body: tuple, out: list | None = None) -> list:
    """Every term written in ``body`` (conditions, and those of the bodies of if/while/for/fork), in order.
    What nests in them (a plan term in a plan term, built at run time) is left to the caller's walk:
    ``variables`` and ``term_height`` take it with a stack of their own, not the C stack."""
    out = [] if out is None else out
    for instr in body:
        if isinstance(instr, If):
            for c, b in instr.branches:
                out.append(c)
                body_terms(b, out)
            if instr.else_body:
                body_terms(instr.else_body, out)
        elif isinstance(instr, (While, For)):
            out.append(instr.cond)
            body_terms(instr.body, out)
        elif isinstance(instr, Fork):
            for b in instr.branches:
                body_terms(b, out)
        else:
            out.extend(instr.terms())
    return out


def body_variables(body: tuple, out: list | None = None) -> list:
    out = [] if out is None else out
    for instr in body:
        if isinstance(instr, If):
            for c, b in instr.branches:
                variables(c, out)
                body_variables(b, out)
            if instr.else_body:
                body_variables(instr.else_body, out)
        elif isinstance(instr, (While, For)):
            variables(instr.cond, out)
            body_variables(instr.body, out)
        elif isinstance(instr, Fork):
            for b in instr.branches:
                body_variables(b, out)
        else:
            for t in instr.terms():
                variables(t, out)
    return out


# -- plans and rules -----------------------------------------------------------------------
_plan_counter = [0]


class Plan:
    """``@label trigger : context <- body.``

    Attributes beside the constructor's: ``atomic`` and ``all_unifs`` (from the label's annotations),
    ``goal_condition`` (Jason 3.2's ``+!g <: C <- body``: the goal is achieved as soon as C holds) and
    ``matcher`` ((trigger variables, compiled context, tail-call key) for deliberation, made on first use
    by ``plan_matcher``; shared by every agent whose plan has the same terms); ``sub_plans`` (Jason(ER)'s
    ``+!g <- body. { sub-plans }``: plans relevant only while this plan's intended means is on an intention;
    their variables of the same name are this plan's, the parser maps them); ``sub_library`` (the
    ``PlanLibrary`` of ``sub_plans`` once the plan is in an agent's library, its father that library) and
    ``scope`` (the library a sub-plan lives in). A plain class, not a dataclass: importing ``dataclasses``
    is a noticeable part of a hello world's start (issue 23)."""

    def __init__(self, trigger: Trigger, context: Term | None = None, body: tuple = (), label: Literal | None = None,
                 source_file: str = "", line: int = 0) -> None:
        self.trigger = trigger
        self.context = context
        self.body = body
        self.label = label
        self.source_file = source_file
        self.line = line
        self.goal_condition: Term | None = None
        self.sub_plans: tuple = ()
        self.sub_library: object = None
        self.scope: object = None
        self.refresh_label_flags()         # atomic, all_unifs, matcher

    def __repr__(self) -> str:
        return (f"Plan(trigger={self.trigger!r}, context={self.context!r}, body={self.body!r}, label={self.label!r}, "
                f"source_file={self.source_file!r}, line={self.line!r}, atomic={self.atomic!r}, "
                f"all_unifs={self.all_unifs!r}, goal_condition={self.goal_condition!r}, sub_plans={self.sub_plans!r})")

    def __getstate__(self) -> dict:
        # as parsed (agentspeak/parse_cache.py): without the matcher (compiled closures, made again on first use)
        # and without the libraries an agent's copy is put in
        return {**self.__dict__, "matcher": None, "sub_library": None, "scope": None}

    def refresh_label_flags(self) -> None:
        annots = self.label.annots if type(self.label) is Literal and self.label.annots else ()
        names = {a.functor for a in annots if isinstance(a, Literal)}
        self.atomic = "atomic" in names
        self.matcher = None  # tail calls depend on atomic
        self.all_unifs = "all_unifs" in names

    def ensure_label(self) -> Literal:
        """Jason gives an unlabelled plan a unique ``p__N`` label."""
        if self.label is None or not self.label.functor:
            _plan_counter[0] += 1
            annots = self.label.annots if self.label is not None else None
            self.label = Literal(f"p__{_plan_counter[0]}", (), annots)
        return self.label

    def copy(self) -> "Plan":
        """A new Plan object over the same terms (each agent's library holds its own plans)."""
        q = Plan(self.trigger, self.context, self.body, self.label, self.source_file, self.line)
        q.goal_condition = self.goal_condition
        q.sub_plans = self.sub_plans
        return q

    def renamed(self) -> "Plan":
        """A copy with fresh variables (used when a plan is stored as a term)."""
        mapping: dict = {}
        p = Plan(self.trigger.rename(mapping),
                 rename(self.context, mapping) if self.context is not None else None,
                 map_body(self.body, lambda t: rename(t, mapping)), self.label,
                 self.source_file, self.line)
        return p

    def resolved(self, b: Bindings, depth: int = 0) -> "Plan":
        """The plan with the bindings applied; nothing in it is evaluated (a plan is code: its
        ``math.random`` runs when the formula runs, not when the plan is handed around as a term).
        ``depth``: how deep the plan sits in a term being resolved (``terms.resolve``)."""
        p = Plan(Trigger(self.trigger.op, self.trigger.kind, substitute(self.trigger.literal, b, depth)),
                 substitute(self.context, b, depth) if self.context is not None else None,
                 map_body(self.body, lambda t: substitute(t, b, depth)),
                 substitute(self.label, b, depth) if self.label is not None else None,
                 self.source_file, self.line)
        p.goal_condition = substitute(self.goal_condition, b, depth) if self.goal_condition is not None else None
        return p

    def __str__(self) -> str:
        text = ""
        if self.label is not None:
            text += "@" + to_str(self.label) + " "
        text += str(self.trigger)
        if self.context is not None:
            text += " : " + to_str(self.context)
        if self.goal_condition is not None:
            text += " <: " + to_str(self.goal_condition)
        if self.body:
            text += " <- " + body_str(self.body)
        return text

    def source_text(self, indent: str = "") -> str:
        """The plan as AgentSpeak source, its sub-plans in a block after it (``.save_agent``)."""
        text = indent + str(self) + "."
        if self.sub_plans:
            inner = "\n".join(p.source_text(indent + "   ") for p in self.sub_plans)
            text += " {\n" + inner + "\n" + indent + "}"
        return text


def plan_variables(plan: Plan) -> list:
    """The variables of a plan: label, trigger, context, goal condition and body."""
    out: list = []
    for t in (plan.label, plan.trigger.literal, plan.context, plan.goal_condition):
        if t is not None:
            variables(t, out)
    return body_variables(plan.body, out)


def with_sub_plans(plan: Plan, subs: list) -> Plan:
    """``plan`` with Jason(ER) sub-plans attached. A sub-plan's variable named as one of the plan's is
    that variable (Jason's unifiers go by name: the sub-plan starts from the bindings the plan had when
    it was selected), at any depth of nesting."""
    names = {v.name: v for v in plan_variables(plan) if v.name != "_"}
    q = plan.copy()
    q.sub_plans = plan.sub_plans + tuple(_share_variables(sp, names) for sp in subs)
    return q


def _share_variables(sub: Plan, names: dict) -> Plan:
    mapping = {v: names[v.name] for v in plan_variables(sub) if v.name in names and names[v.name] is not v}
    r = sub.resolved(mapping) if mapping else sub.copy()
    inner = dict(names)
    inner.update((v.name, v) for v in plan_variables(r) if v.name != "_")
    r.sub_plans = tuple(_share_variables(s, inner) for s in sub.sub_plans)
    return r


def plan_matcher(plan: Plan) -> tuple:
    """What deliberation needs of a plan, worked out once: ``(vars, context, tail)``.

    ``vars`` is the tuple of trigger arguments when they are distinct variables and the trigger has
    no annotations (then an event binds them one to one, without unification), else None;
    ``context`` is the compiled context closure, or None for a plan without one; ``tail`` is
    ``(functor, arity)`` of a non-atomic ``+!g`` plan (a tail call replaces a caller with the
    same), else None."""
    from agentspeak.solver import compiled

    lit = plan.trigger.literal
    tvars = None
    if (type(lit) is Literal and lit.annots is None and lit.annot_tail is None
            and all(type(a) is Var for a in lit.args) and len(set(map(id, lit.args))) == len(lit.args)):
        tvars = lit.args
    trig = plan.trigger
    tail = None  # the key of a tail call's caller and callee: (functor, arity) of a non-atomic +!g plan
    if trig.op == ADD and trig.kind == ACHIEVE and type(lit) is Literal and not plan.atomic:
        tail = (lit.functor, len(lit.args))
    plan.matcher = (tvars, compiled(plan.context) if plan.context is not None else None, tail)
    return plan.matcher


class Rule:
    """``head :- body.`` (a non-ground initial belief ``b(X).`` becomes ``b(X) :- true``)."""

    def __init__(self, head: Literal, body: Term, source_file: str = "", line: int = 0, nvars: int = 0) -> None:
        self.head, self.body, self.source_file, self.line, self.nvars = head, body, source_file, line, nvars

    def copy(self) -> "Rule":
        return Rule(self.head, self.body, self.source_file, self.line, self.nvars)

    def __repr__(self) -> str:
        return (f"Rule(head={self.head!r}, body={self.body!r}, source_file={self.source_file!r}, line={self.line!r}, "
                f"nvars={self.nvars!r})")

    def __str__(self) -> str:
        return f"{to_str(self.head)} :- {to_str(self.body)}"


class PlanTerm:
    """A plan, trigger, body or rule written as a term: ``{ +!g <- b }``, ``{ +b }``, ``{ a; b }``.

    ``plan`` is set for plans and triggers (a trigger-only term is a plan without body);
    ``body`` for a body term; ``rule`` for a rule term.
    """

    __slots__ = ("plan", "body", "rule", "_vars", "bare", "_height")

    def __init__(self, plan: Plan | None = None, body: tuple | None = None, rule: Rule | None = None,
                 bare: bool = False) -> None:
        self.plan, self.body, self.rule = plan, body, rule
        self._vars = None  # its variables, worked out on the first resolve
        self._height = -1  # how deep it nests (``term_height``), worked out when first resolved unchanged
        # a body taken out of a plan or of a longer body (``{@L +!T : C <- B}``, ``{ F; Rest }``) prints
        # without braces, as Jason's (its PlanBody is not "a term"): ``.substring(".send(", B, 0)``
        self.bare = bare

    def _bound_in(self, b: Bindings) -> bool:
        """Is any variable of this term bound in ``b``? (A plan term handed around, e.g. by
        .relevant_plans, usually has none: resolving it is then a no-op, not a copy of the plan.)"""
        vs = self._vars
        if vs is None:
            vs = self._vars = tuple(variables(self))
        for v in vs:
            if v in b:
                return True
        return False

    def as_trigger(self) -> Trigger | None:
        """The trigger this term stands for (``{+!g}`` or a one-formula body such as ``{+b}``)."""
        if self.plan is not None:
            return self.plan.trigger
        if self.body is not None and len(self.body) == 1:
            instr = self.body[0]
            if isinstance(instr, TriggerInstr):
                return instr.trigger
            if isinstance(instr, AddBel):
                return Trigger(ADD, BEL, instr.term)
            if isinstance(instr, DelBel):
                return Trigger(DEL, BEL, instr.term)
        return None

    def as_plan(self) -> Plan | None:
        if self.plan is not None:
            return self.plan
        trig = self.as_trigger()
        return Plan(trig) if trig is not None else None

    def resolve(self, b: Bindings, depth: int = 0) -> "PlanTerm":
        if self.body is not None:
            # Jason's PlanBodyImpl.capply: a body term gets the bindings, and the arithmetic and functions
            # of its formulas are computed (`{ !assert_equals(1, .count(b(_))) }` stored in a belief
            # holds the count of that moment, so two such beliefs can be equal: Jason's own test manager
            # counts its asserts that way). Conditions of if/while/for stay code.
            if not self._bound_in(b) and not self._has_calls():
                return self._unchanged(depth)
            return PlanTerm(body=tuple([_capply_instr(i, b, depth + 1) for i in self.body]), bare=self.bare)
        if not self._bound_in(b):
            return self._unchanged(depth)
        if self.plan is not None:
            return PlanTerm(plan=self.plan.resolved(b, depth + 1))
        r = self.rule
        return PlanTerm(rule=Rule(substitute(r.head, b, depth + 1), substitute(r.body, b, depth + 1), r.source_file,
                                  r.line))

    def _unchanged(self, depth: int) -> "PlanTerm":
        """This term, as it is, at ``depth`` of a term being resolved: its own nesting counts too (a plan term
        resolved unchanged is not walked, so a goal wrapping the last one in a new one on each call built
        them 18,000 deep, and the walkers overflowed the C stack of the compiled build)."""
        if self._height < 0:
            self._height = term_height(self)
        if depth + self._height > MAX_TERM_DEPTH:
            raise RecursionError(f"a term nested deeper than {MAX_TERM_DEPTH} levels")
        return self

    def _has_calls(self) -> bool:
        """Does a simple formula of this body term hold arithmetic or a function call?"""
        for instr in self.body:
            if not isinstance(instr, (If, While, For, Fork)):
                for t in instr.terms():
                    if _holds_call(t):
                        return True
        return False

    def rename(self, mapping: dict) -> "PlanTerm":
        if self.plan is not None:
            p = self.plan
            q = Plan(p.trigger.rename(mapping), rename(p.context, mapping) if p.context is not None else None,
                     map_body(p.body, lambda t: rename(t, mapping)),
                     rename(p.label, mapping) if p.label is not None else None, p.source_file, p.line)
            if p.goal_condition is not None:
                q.goal_condition = rename(p.goal_condition, mapping)
            return PlanTerm(plan=q)
        if self.body is not None:
            return PlanTerm(body=map_body(self.body, lambda t: rename(t, mapping)), bare=self.bare)
        r = self.rule
        return PlanTerm(rule=Rule(rename(r.head, mapping), rename(r.body, mapping), r.source_file, r.line))

    def subterms(self) -> list:
        out: list = []
        if self.plan is not None:
            if self.plan.label is not None:
                out.append(self.plan.label)
            out.append(self.plan.trigger.literal)
            if self.plan.context is not None:
                out.append(self.plan.context)
            body = self.plan.body
        elif self.body is not None:
            body = self.body
        else:
            return [self.rule.head, self.rule.body]
        return body_terms(body, out)   # terms, not their variables: nested plan terms on the caller's stack

    def unify_with(self, other: object, b: Bindings, trail: list) -> bool:
        """Structural, as Jason's plan terms: label, trigger, context (none is ``true``) and body, where
        a variable formula unifies with the other's formula and a variable last formula with the
        rest of the other body (``{ T; _ }``; ``{@L +!g : C <- B}``)."""
        if not isinstance(other, PlanTerm):
            return False
        from agentspeak.unify import unify
        x, y = self.as_plan_parts(), other.as_plan_parts()
        if x is None or y is None:
            if self.rule is not None and other.rule is not None:
                return (unify(self.rule.head, other.rule.head, b, trail)
                        and unify(self.rule.body, other.rule.body, b, trail))
            return False
        (xl, xt, xc, xb), (yl, yt, yc, yb) = x, y
        if xt is not None or yt is not None:
            if xt is None or yt is None or xt.op != yt.op or xt.kind != yt.kind:
                return False
            if not unify(xt.literal, yt.literal, b, trail):
                return False
        if xl is not None and yl is not None and not unify(xl, yl, b, trail):
            return False
        if (xc is not None or yc is not None) and not unify(_TRUE if xc is None else xc,
                                                              _TRUE if yc is None else yc, b, trail):
            return False
        return unify_bodies(xb, yb, b, trail)

    def as_plan_parts(self) -> tuple | None:
        """(label, trigger, context, body) of a plan or body term; None for a rule term."""
        if self.plan is not None:
            p = self.plan
            return (p.label, p.trigger, p.context, p.body)
        if self.body is not None:
            trig = self.as_trigger() if len(self.body) == 1 and isinstance(self.body[0], TriggerInstr) else None
            return (None, trig, None, () if trig is not None else self.body)
        return None

    def __eq__(self, other: object) -> bool:  # braces or not: the same term (Jason's equals)
        return isinstance(other, PlanTerm) and self._text() == other._text()

    def __hash__(self) -> int:
        return hash(self._text())

    def _text(self) -> str:
        if self.plan is not None:
            return str(self.plan)
        if self.body is not None:
            return body_str(self.body)
        return str(self.rule)

    def __str__(self) -> str:
        return self._text() if self.bare else "{ " + self._text() + " }"

    __repr__ = __str__


_TRUE = Literal("true")


def _holds_call(t: Term) -> bool:
    tt = type(t)
    if tt is Func or tt is Arith:
        return True
    if tt is Literal:
        return any(_holds_call(x) for x in t.args) or bool(t.annots) and any(_holds_call(x) for x in t.annots)
    if tt is Cons:
        while type(t) is Cons:
            if _holds_call(t.head):
                return True
            t = t.tail
        return False
    if tt is Rel or tt is And or tt is Or:
        return _holds_call(t.left) or _holds_call(t.right)
    if tt is Not:
        return _holds_call(t.arg)
    return False


def _capply_instr(instr: "Instr", b: Bindings, depth: int = 0) -> "Instr":
    if isinstance(instr, (If, While, For, Fork)):
        return instr.map_terms(lambda t: substitute(t, b, depth))
    return instr.map_terms(lambda t: _capply(t, b, depth))


def _capply(t: Term, b: Bindings, depth: int = 0) -> Term:
    """``resolve`` (bindings applied, ground arithmetic and functions computed); a term that cannot be
    computed now is kept as it is, with the bindings applied (Jason logs it and keeps the term)."""
    try:
        return resolve(t, b, depth)
    except RecursionError:
        raise                # too deep: not "not computable now" (substitute would walk it as deep)
    except Exception:  # noqa: BLE001 - an expression that fails now stays code, as in Jason
        return substitute(t, b, depth)


def substitute(t: Term, b: Bindings, depth: int = 0) -> Term:
    """``t`` with the bindings applied, evaluating nothing (``resolve`` computes arithmetic and calls
    functions; inside a plan term those are code that runs later). ``depth``: as ``terms.resolve``'s, the
    same limit (``MAX_TERM_DEPTH``): a plan term can nest plan terms at run time as a literal can nest literals."""
    if depth > MAX_TERM_DEPTH:
        raise RecursionError(f"a term nested deeper than {MAX_TERM_DEPTH} levels")
    tt = type(t)
    d = depth + 1
    if tt is Var:
        v = b.get(t)
        while type(v) is Var:
            t, v = v, b.get(v)
        return t if v is None else substitute(v, b, depth)
    if tt is Literal:
        if not t.args and t.annots is None and t.annot_tail is None:
            return t
        if t.annot_tail is not None and b.get(t.annot_tail) is not None:
            return resolve(t, b, depth)
        return Literal(t.functor, tuple([substitute(a, b, d) for a in t.args]),
                       tuple([substitute(a, b, d) for a in t.annots]) if t.annots else None, t.neg, t.annot_tail)
    if tt is Func:
        return Func(t.name, tuple([substitute(a, b, d) for a in t.args]), t.spec)
    if tt is Arith:
        return Arith(t.op, substitute(t.left, b, d), substitute(t.right, b, d) if t.right is not None else None)
    if tt is Rel:
        return Rel(t.op, substitute(t.left, b, d), substitute(t.right, b, d))
    if tt is And:
        return And(substitute(t.left, b, d), substitute(t.right, b, d))
    if tt is Or:
        return Or(substitute(t.left, b, d), substitute(t.right, b, d))
    if tt is Not:
        return Not(substitute(t.arg, b, d))
    if tt is Cons:
        heads = []
        while type(t) is Cons:
            heads.append(substitute(t.head, b, d))
            t = t.tail
            while type(t) is Var and b.get(t) is not None:
                t = b[t]
        tail = substitute(t, b, depth) if t is not NIL else NIL
        for h in reversed(heads):
            tail = Cons(h, tail)
        return tail
    return resolve(t, b, depth)


def _formula_term(instr) -> Term:
    """What a variable written as a formula (``{ H; R }``) unifies with: the whole formula, ``?b(X)``
    or ``!g(1)``, as a one-formula body (Jason's Unifier: ``pb2.getHead()``), so executing ``H`` runs it
    (demos/meta-programming). A typed variable (``{ !G; R }``) unifies with the term only."""
    return PlanTerm(body=(instr,), bare=True)


def unify_bodies(xs: tuple, ys: tuple, b: Bindings, trail: list) -> bool:
    from agentspeak.unify import unify
    if ys and isinstance(ys[-1], ExecVar) and not (xs and isinstance(xs[-1], ExecVar)):
        xs, ys = ys, xs  # the side with a variable tail leads
    n = len(xs)
    for i, x in enumerate(xs):
        if i == n - 1 and type(x) is ExecVar and type(x.term) is Var and (len(ys) != n or type(ys[i]) is not ExecVar):
            value = resolve(x.term, b)
            if type(value) is Var:
                return unify(value, PlanTerm(body=ys[i:], bare=True), b, trail)  # the rest of the body
        if i >= len(ys):
            return False
        y = ys[i]
        if type(x) is ExecVar:
            if not unify(x.term, _formula_term(y) if type(y) is not ExecVar else y.term, b, trail):
                return False
            continue
        if type(y) is ExecVar:
            if not unify(_formula_term(x), y.term, b, trail):
                return False
            continue
        if type(x) is not type(y):
            return False
        if isinstance(x, _OneTerm):
            if not unify(x.term, y.term, b, trail):
                return False
        elif str(x.map_terms(lambda t: resolve(t, b))) != str(y.map_terms(lambda t: resolve(t, b))):
            return False
    return len(xs) == len(ys)


class TriggerInstr(Instr):
    """A trigger written where a body formula is expected: only valid inside ``{ ... }`` terms."""

    __slots__ = ("trigger",)

    def __init__(self, trigger: Trigger, line: int = 0) -> None:
        self.trigger, self.line = trigger, line

    def map_terms(self, f):
        return TriggerInstr(Trigger(self.trigger.op, self.trigger.kind, f(self.trigger.literal)), self.line)

    def terms(self) -> list:
        return [self.trigger.literal]

    def __str__(self) -> str:
        return str(self.trigger)


class Program:
    """Everything one .asl file (and its includes) declares, in source order: ``beliefs`` (ground literals),
    ``rules`` (Rule), ``goals`` (literals of initial goals), ``plans`` (Plan)."""

    _FIELDS = ("beliefs", "rules", "goals", "plans", "source_file", "warnings")

    def __init__(self, beliefs: list | None = None, rules: list | None = None, goals: list | None = None,
                 plans: list | None = None, source_file: str = "", warnings: list | None = None) -> None:
        self.beliefs = [] if beliefs is None else beliefs
        self.rules = [] if rules is None else rules
        self.goals = [] if goals is None else goals
        self.plans = [] if plans is None else plans
        self.source_file = source_file
        self.warnings = [] if warnings is None else warnings

    def __eq__(self, other: object) -> bool:
        if type(other) is not Program:
            return NotImplemented
        return all(getattr(self, f) == getattr(other, f) for f in self._FIELDS)

    __hash__ = None  # type: ignore[assignment]  (mutable, compared by value)

    def __repr__(self) -> str:
        return "Program(" + ", ".join(f"{f}={getattr(self, f)!r}" for f in self._FIELDS) + ")"


def copy_program(program: Program) -> Program:
    """A program of new Plan and Rule objects over the same (immutable) terms and instructions: what each
    agent of a shared source gets (plans hold per-agent labels and flags)."""
    return Program(
        beliefs=list(program.beliefs),
        rules=[r.copy() for r in program.rules],
        goals=list(program.goals),
        plans=[p.copy() for p in program.plans],
        source_file=program.source_file,
        warnings=list(program.warnings))


def is_var(t: Term) -> bool:
    return type(t) is Var




class PyCall(Instr):
    """A Python step inserted by the runtime itself (e.g. answering an ask after a ``+?q`` plan)."""

    __slots__ = ("fn",)

    def __init__(self, fn, line: int = 0) -> None:
        self.fn, self.line = fn, line

    def map_terms(self, f):
        return self

    def __str__(self) -> str:
        return f"<python {getattr(self.fn, '__name__', 'call')}>"
