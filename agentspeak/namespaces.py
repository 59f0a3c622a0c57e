"""Jason's modules at parse time: which name space each literal of a file is in.

A file is parsed into a module name space (``default``, or the one given by ``{ include("f.asl", ns) }`` /
``.include("f.asl", ns)``). As in Jason's parser (``as2j``): a literal written without a name space is in
the *current* name space when it stands as a formula (a belief, a rule's head or body, a trigger, a goal, a
body formula, a context, a plan label) and in ``default`` when it is a term (an argument, an annotation, a
list element, an operand of a relational expression); internal actions are in ``default``. ``::lit`` is in
the module's name space (``this_ns``, also as an atom in a term), ``default::lit`` in the default one.
``{ begin namespace(ns[, local|global]) } ... { end }`` changes the current name space for the clauses
between; ``{ namespace(ns, local) }`` declares a local name space ahead: a local name space ``ns`` is
renamed ``#<n>ns``, unique per parse (each inclusion of a module has its own private beliefs and goals).

The grammar gives every literal its written name space in the functor's text (``tv::cfp``, ``::cfp``,
``default::cfp``) and a variable name space as ``NsTerm``; ``NsScope.clause`` resolves them. Files without
``::`` or ``this_ns`` in the default name space need nothing of this (``needs_scope``).
"""
from __future__ import annotations

import itertools

from agentspeak.program import Plan, PlanTerm, Rule, Trigger, map_body, with_sub_plans
from agentspeak.terms import (
    DEFAULT_NS_NAME, LOCAL_NS_PREFIX, NS_SEP, And, AnnotatedVar, Arith, Cons, Func, Literal, Not, NsTerm, Or, Rel,
    Term, Var, in_ns, ns_atom,
)

_ids = itertools.count(1)

# Jason's ASSyntax keywords: stay in the default name space wherever they are written
_KEYWORDS = frozenset((("atomic", 0), ("breakpoint", 0), ("all_unifs", 0), ("default", 0), ("this_ns", 0),
                       ("source", 1), ("self", 0), ("percept", 0)))


def unique_ns_id() -> int:
    """Jason's ``NameSpace.getUniqueID``: numbers local name spaces (``#3priv``) and the name spaces that
    ``.include(F, NS)`` makes for an unbound ``NS`` (``ns4``)."""
    return next(_ids)


def needs_scope(text: str, module_ns: str) -> bool:
    return module_ns != DEFAULT_NS_NAME or NS_SEP in text or "this_ns" in text


class NsError(ValueError):
    """A namespace directive with wrong arguments."""


class NsScope:
    """The name-space state of one parse (Jason's ``namespace``, ``thisnamespace`` and the local map of
    its ``NameSpace`` directive)."""

    def __init__(self, module_ns: str = DEFAULT_NS_NAME) -> None:
        self.module = module_ns
        self.current = module_ns   # for literals written without a name space
        self.this = module_ns      # ``::lit`` and ``this_ns``
        self.local: dict[str, str] = {}
        self._stack: list[tuple[str, str]] = []
        self.declared_local = False

    # -- directives -------------------------------------------------------------------------------
    def begin(self, directive: Literal) -> None:
        """``{ begin namespace(ns[, local|global]) }`` (also ``{ namespace(ns, local) }``, begun and ended
        at once: it declares ``ns`` local for the rest of the file)."""
        ns = self._directive_ns(directive)
        self._stack.append((self.current, self.this))
        self.current = self.this = ns

    def end(self) -> None:
        if self._stack:
            self.current, self.this = self._stack.pop()

    def declare(self, directive: Literal) -> None:
        self.begin(directive)
        self.end()

    def _directive_ns(self, directive: Literal) -> str:
        args = directive.args
        if not args or len(args) > 2 or not _is_atom(args[0]):
            raise NsError(f"expected namespace(Atom) or namespace(Atom, local|global), got {directive}")
        ns = args[0].functor
        if len(args) == 2:
            kind = args[1].functor if _is_atom(args[1]) else None
            if kind not in ("local", "global"):
                raise NsError(f"the second argument of {directive} must be local or global")
            if kind == "global":
                self.local.pop(ns, None)
            elif ns not in self.local:
                self.local[ns] = f"{LOCAL_NS_PREFIX}{unique_ns_id()}{ns}"
                self.declared_local = True
        return ns

    # -- clauses -------------------------------------------------------------------------------------
    def literal_ns(self, written: str | None) -> str:
        """The name space of a literal written with ``written::`` (None: written without one, at a formula)."""
        if written is None:
            ns = self.current
        elif written == "" or written == "this_ns":
            ns = self.this
        else:
            ns = written
        return self.local.get(ns, ns)

    def clause(self, kind: str, value):
        """The parser's item ``(kind, value)`` with its name spaces resolved."""
        cur = self.current
        if kind in ("belief", "goal"):
            return self.term(value, cur, True)
        if kind == "rule":
            r = value
            return Rule(self.term(r.head, cur, True), self.term(r.body, cur, True), r.source_file, r.line, r.nvars)
        if kind == "plan":
            return self.plan(value, cur)
        if kind == "sub_plans":
            return [self.plan(p, cur) for p in value]
        return value

    def plan(self, p: Plan, cur: str) -> Plan:
        trig = p.trigger
        label = p.label
        if type(label) is Literal and label.functor and NS_SEP not in label.functor and cur != DEFAULT_NS_NAME:
            # Jason names a plan's label in the current name space: `@p1` of a module in tv is tv::p1
            label = Literal(in_ns(cur, label.functor), label.args, label.annots, label.neg, label.annot_tail)
        q = Plan(Trigger(trig.op, trig.kind, self.term(trig.literal, cur, True)),
                 self.term(p.context, cur, True) if p.context is not None else None,
                 map_body(p.body, lambda t: self.term(t, cur, True)), label, p.source_file, p.line)
        q.goal_condition = self.term(p.goal_condition, cur, True) if p.goal_condition is not None else None
        if p.sub_plans:
            q = with_sub_plans(q, [self.plan(sp, cur) for sp in p.sub_plans])
        return q

    def term(self, t: Term, cur: str, formula: bool) -> Term:
        """``t`` with its literals' name spaces resolved; ``formula``: t stands where a formula does."""
        tt = type(t)
        if tt is Literal:
            return self._literal(t, cur, formula)
        if tt is Cons:
            items = []
            while type(t) is Cons:
                items.append(self.term(t.head, DEFAULT_NS_NAME, False))
                t = t.tail
            out = self.term(t, DEFAULT_NS_NAME, False)
            for x in reversed(items):
                out = Cons(x, out)
            return out
        if tt is And:
            return And(self.term(t.left, cur, formula), self.term(t.right, cur, formula))
        if tt is Or:
            return Or(self.term(t.left, cur, formula), self.term(t.right, cur, formula))
        if tt is Not:
            return Not(self.term(t.arg, cur, formula))
        if tt is Rel:  # operands are terms (Jason drops the current name space of a relation's operands)
            return Rel(t.op, self.term(t.left, DEFAULT_NS_NAME, False), self.term(t.right, DEFAULT_NS_NAME, False))
        if tt is Arith:
            return Arith(t.op, self.term(t.left, DEFAULT_NS_NAME, False),
                         self.term(t.right, DEFAULT_NS_NAME, False) if t.right is not None else None)
        if tt is Func:
            return Func(t.name, tuple(self.term(a, DEFAULT_NS_NAME, False) for a in t.args), t.spec)
        if tt is AnnotatedVar:
            t = AnnotatedVar(t.var, tuple(self.term(a, DEFAULT_NS_NAME, False) for a in t.annots), t.annot_tail)
        if (tt is Var or tt is AnnotatedVar) and formula and cur != DEFAULT_NS_NAME:
            # a variable written as a formula is of the module's name space, as Jason's `var(NS)`: a catch-all
            # `-!G[error(E)]` of a module handles the failures of its goals only, and `!G` posts a goal of it
            # (mapped when the name space is local, where Jason's parser keeps the written name)
            return NsTerm(ns_atom(self.local.get(cur, cur)), t)
        if tt is AnnotatedVar:
            return t
        if tt is NsTerm:
            return self._ns_term(t)
        if tt is PlanTerm:
            return self._plan_term(t, cur if formula else DEFAULT_NS_NAME)
        return t

    def _literal(self, t: Literal, cur: str, formula: bool) -> Literal:
        f = t.functor
        args = tuple(self.term(a, DEFAULT_NS_NAME, False) for a in t.args) if t.args else ()
        annots = tuple(self.term(a, DEFAULT_NS_NAME, False) for a in t.annots) if t.annots else None
        if not formula and f == "this_ns" and not args and not t.neg and annots is None:
            return ns_atom(self.this)
        if f and f[0] != "'" and NS_SEP in f:
            written, _, name = f.partition(NS_SEP)
            ns = DEFAULT_NS_NAME if written == DEFAULT_NS_NAME else self.literal_ns(written)
        else:
            name = f
            if formula and f and not _is_internal_action(f) and (f, len(args)) not in _KEYWORDS:
                ns = self.local.get(cur, cur)
            else:
                ns = DEFAULT_NS_NAME
            if formula and f == ".include" and len(args) == 1 and cur != DEFAULT_NS_NAME:
                args += (ns_atom(cur),)  # Jason's .include loads into the name space it is written in
        functor = in_ns(ns, name)
        if functor == f and args == t.args and annots == t.annots:
            return t
        return Literal(functor, args, annots, t.neg, t.annot_tail)

    def _ns_term(self, t: NsTerm) -> Term:
        body = t.body
        if type(body) is Literal:  # a variable name space: only the arguments are terms to look at
            body = self._literal(body, DEFAULT_NS_NAME, False)
        elif type(body) is AnnotatedVar:
            body = self.term(body, DEFAULT_NS_NAME, False)
        ns = t.ns
        if type(ns) is Literal:  # `ns::X`, `::X`, `default::X`
            name = DEFAULT_NS_NAME if ns.functor == DEFAULT_NS_NAME else self.literal_ns(ns.functor)
            if name == DEFAULT_NS_NAME:
                return body
            ns = ns_atom(name)
        return NsTerm(ns, body)

    def _plan_term(self, t: PlanTerm, cur: str) -> PlanTerm:
        if t.plan is not None:
            return PlanTerm(plan=self.plan(t.plan, cur), bare=t.bare)
        if t.body is not None:
            return PlanTerm(body=map_body(t.body, lambda x: self.term(x, cur, True)), bare=t.bare)
        r = t.rule
        return PlanTerm(rule=Rule(self.term(r.head, cur, True), self.term(r.body, cur, True), r.source_file, r.line,
                                  r.nvars), bare=t.bare)


def _is_atom(t: Term) -> bool:
    return type(t) is Literal and not t.args and not t.neg and t.annots is None


def _is_internal_action(functor: str) -> bool:
    return "." in functor and functor[0] != "'"
