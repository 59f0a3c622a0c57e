"""Solving logical formulas against an agent's belief base: contexts, test goals, rules.

An explicit machine (a continuation list and a choice-point stack), not Python recursion, so rules
recursing 100,000 levels deep or walking long lists never hit the recursion limit. Bindings live in
the caller's dict; a trail undoes them on backtracking.

``solve(kb, formula, b)`` is a generator: each ``next`` leaves one solution's bindings in ``b``.
Stopping early keeps the bindings of the last solution (what a plan context or a test goal wants);
running to exhaustion undoes everything.
"""
from __future__ import annotations

import logging
import operator
from typing import Iterator, Protocol

from agentspeak.terms import (
    _EXACT, INT_OPS, NS_SEP, And, AnnotatedVar, Arith, ArithmeticError_, Cons, Func, Literal, Not, NsTerm, Or, Rel,
    Term, Var, compare, deref, in_ns, is_list, list_items, make_list, resolve, split_ns, to_str,
)
from agentspeak.copier import rule_copier
from agentspeak.unify import in_other_ns, undo, unify, unify_annots_all

log = logging.getLogger("faultmas.agentspeak")


class FactIndex(Protocol):
    """What compiled formulas read of a belief base (``agentspeak.beliefs.BeliefBase``, which imports this
    layer's neighbours, not the other way round): its indexes by ``(functor, arity)`` and their lookup."""

    _facts: dict
    _rules: dict

    def candidates_by_key(self, key: tuple, lit: Literal, b: dict) -> list: ...
    def literals(self) -> Iterator[Literal]: ...


class KnowledgeBase(Protocol):
    """What the solver needs from an agent: facts, rules and internal actions usable in formulas
    (compiled formulas go to the belief base ``bb`` directly)."""

    bb: FactIndex

    def candidates(self, lit: Literal, b: dict) -> list: ...
    def rules_for(self, lit: Literal) -> list: ...
    def call_internal(self, lit: Literal, b: dict, trail: list) -> Iterator[None]: ...


class SolveError(Exception):
    """A formula that cannot be evaluated (non-numeric arithmetic, unknown internal action...)."""

    def __init__(self, error: str, message: str) -> None:
        super().__init__(message)
        self.error = error
        self.message = message


class _Cont:
    """A linked list of goals still to prove."""

    __slots__ = ("goal", "next")

    def __init__(self, goal: Term, next_: "_Cont | None") -> None:
        self.goal, self.next = goal, next_


def solve(kb: KnowledgeBase, formula: Term, b: dict, trail: list | None = None) -> Iterator[None]:
    if trail is None:
        trail = []
    base = len(trail)
    # each choice point: (kind, data..., continuation, trail mark)
    choices: list = []
    cont: _Cont | None = _Cont(formula, None)
    while True:
        if cont is None:
            yield None
            # ask for the next solution: backtrack
            ok = False
        else:
            goal = cont.goal
            cont = cont.next
            ok = True
            tg = type(goal)
            if tg is Var:
                goal = deref(goal, b)
                tg = type(goal)
                if tg is Var:
                    # `X` free as a query: each belief of the default name space, with its annotations
                    # (Jason's VarTerm.logicalConsequence; `.findall(X, X, L)`)
                    bb = getattr(kb, "bb", None)
                    facts = bb.in_namespace(DEFAULT_NS.functor) if bb is not None else []
                    if facts:
                        choices.append((1, goal, facts, 0, (), 0, cont, len(trail), None))
                    tg = _AnyBelief
            if tg is And:
                cont = _Cont(goal.left, _Cont(goal.right, cont))
                continue
            if tg is Literal:
                functor = goal.functor
                if not goal.args and not goal.neg:
                    if functor == "true":
                        continue
                    if functor == "false":
                        ok = False
                if ok and "." in functor and not goal.neg:
                    gen = kb.call_internal(goal, b, trail)
                    choices.append((2, gen, cont, len(trail)))
                    ok = False  # fall through to backtracking, which pulls the first solution
                elif ok:
                    facts = kb.candidates(goal, b)
                    rules = kb.rules_for(goal)
                    if not facts and not rules:
                        ok = False
                    else:
                        choices.append((1, goal, facts, 0, rules, 0, cont, len(trail), None))
                        ok = False
            elif tg is Rel:
                try:
                    ok = _rel(kb, goal, b, trail)
                except ArithmeticError_ as exc:
                    raise SolveError("wrong_arguments", str(exc)) from None
                if ok:
                    continue
            elif tg is Or:
                choices.append((3, goal.right, cont, len(trail)))
                cont = _Cont(goal.left, cont)
                continue
            elif tg is Not:
                mark = len(trail)
                inner = solve(kb, goal.arg, b, trail)
                found = next(inner, False) is None
                inner.close()
                undo(b, trail, mark)  # negation as failure binds nothing
                if found:
                    ok = False
                else:
                    continue
            elif tg is bool:
                ok = goal
                if ok:
                    continue
            elif tg is AnnotatedVar:
                # `X[a]` as a query: X's value with those annotations, or, X free, any belief with them
                value = resolve(goal, b)
                if type(value) is Literal:
                    cont = _Cont(value, cont)
                    continue
                bb = getattr(kb, "bb", None)
                facts = list(bb.literals()) if bb is not None else []
                if facts:
                    choices.append((1, goal, facts, 0, [], 0, cont, len(trail), None))
                ok = False
            elif tg is NsTerm:
                # `NS::b(X)`: with NS bound, the literal of that name space; free, b(X) in every name space
                value = resolve(goal, b)
                if type(value) is Literal:
                    cont = _Cont(value, cont)
                    continue
                if type(value) is not NsTerm:
                    raise SolveError("wrong_arguments", f"'{to_str(goal)}' is not a formula")
                bb = getattr(kb, "bb", None)
                facts, rules = bb.in_every_ns(value.body) if bb is not None else ([], [])
                if facts or rules:
                    choices.append((1, value, facts, 0, rules, 0, cont, len(trail), None))
                ok = False
            elif tg is _AnyBelief:
                ok = False  # its choice point is made: backtracking tries the beliefs
            elif tg is str or tg is int or tg is float or tg is Cons:
                raise SolveError("wrong_arguments", f"'{to_str(goal)}' is not a formula")
            else:
                raise SolveError("wrong_arguments", f"'{to_str(goal)}' is not a formula")
            if ok:
                continue
        # ---- backtrack: resume the most recent choice point
        while True:
            if not choices:
                undo(b, trail, base)
                return
            cp = choices[-1]
            kind = cp[0]
            if kind == 1:
                _, goal, facts, fi, rules, ri, ccont, mark, annot_gen = cp
                if annot_gen is not None:
                    # more ways to match annotations of the same belief: the generator undoes what was bound
                    # after its own marks (the continuation's bindings too); the arguments' stay bound
                    try:
                        next(annot_gen)
                        cont = ccont
                        break
                    except StopIteration:
                        undo(b, trail, mark)
                        choices[-1] = (1, goal, facts, fi, rules, ri, ccont, mark, None)
                        continue
                undo(b, trail, mark)
                matched = False
                while fi < len(facts):
                    fact = facts[fi]
                    fi += 1
                    if goal.annots is not None and _annots_have_vars(goal):
                        if not unify(goal.without_annots(), fact, b, trail):
                            undo(b, trail, mark)
                            continue
                        gen = unify_annots_all(goal, fact, b, trail)
                        try:
                            next(gen)
                        except StopIteration:
                            undo(b, trail, mark)
                            continue
                        choices[-1] = (1, goal, facts, fi, rules, ri, ccont, mark, gen)
                        matched = True
                        break
                    if unify(goal, fact, b, trail):
                        choices[-1] = (1, goal, facts, fi, rules, ri, ccont, mark, None)
                        matched = True
                        break
                    undo(b, trail, mark)
                if matched:
                    cont = ccont
                    break
                while ri < len(rules):
                    rule = rules[ri]
                    ri += 1
                    copier = rule.__dict__.get("_copier") or rule_copier(rule)
                    head, body = copier()
                    if unify(goal, head, b, trail):
                        if fi >= len(facts) and ri >= len(rules):
                            choices.pop()  # last alternative: no choice point left (keeps the stack flat)
                        else:
                            choices[-1] = (1, goal, facts, fi, rules, ri, ccont, mark, None)
                        cont = _Cont(body, ccont)
                        matched = True
                        break
                    undo(b, trail, mark)
                if matched:
                    break
                choices.pop()
                continue
            if kind == 2:
                _, gen, ccont, mark = cp
                undo(b, trail, mark)
                try:
                    next(gen)
                except StopIteration:
                    choices.pop()
                    continue
                cont = ccont
                break
            # kind 3: the right branch of an Or
            _, right, ccont, mark = cp
            undo(b, trail, mark)
            choices.pop()
            cont = _Cont(right, ccont)
            break


class _AnyBelief:
    """The type the machine gives a free variable used as a query once its choice point is made."""


def _annots_have_vars(goal: Literal) -> bool:
    from agentspeak.terms import is_ground
    return not all(is_ground(a) for a in goal.annots) or goal.annot_tail is not None


def solve_first(kb: KnowledgeBase, formula: Term, b: dict) -> bool:
    """Find one solution, keeping its bindings in ``b`` (compiled closures; see below)."""
    return compiled(formula)(kb, b, [], _true_k)


def _rel(kb: KnowledgeBase, rel: Rel, b: dict, trail: list) -> bool:
    op = rel.op
    left = rel.left
    if type(left) is Var:
        left = deref(left, b)
    if type(left) is not int and type(left) is not float:
        left = resolve(left, b)
    right = rel.right
    if type(right) is Var:
        right = deref(right, b)
    if type(right) is not int and type(right) is not float:
        right = resolve(right, b)
    if (op == "<" or op == ">" or op == "<=" or op == ">=") and type(left) in _NUMS and type(right) in _NUMS:
        if op == "<":
            return left < right
        if op == ">":
            return left > right
        if op == "<=":
            return left <= right
        return left >= right
    if op == "=":
        if type(right) is Func or type(left) is Func:
            raise ArithmeticError_(f"{to_str(rel, b)}: a function argument is unbound")
        return unify(left, right, b, trail)
    if op == "==":
        return compare_equal(left, right)
    if op == "\\==":
        return not compare_equal(left, right)
    if op == "=..":
        return _univ(left, right, b, trail)
    if type(left) in _UNEVALUATED or type(right) in _UNEVALUATED:
        raise ArithmeticError_(f"cannot compare {to_str(left)} {op} {to_str(right)}: unbound variable")
    c = compare(left, right)
    if op == "<":
        return c < 0
    if op == "<=":
        return c <= 0
    if op == ">":
        return c > 0
    if op == ">=":
        return c >= 0
    raise ArithmeticError_(f"unknown relational operator {op}")


def compare_equal(a: Term, c: Term) -> bool:
    if type(a) in (int, float) and type(c) in (int, float):
        return a == c
    return a == c


DEFAULT_NS = Literal("default")
_TRUE_ATOM = Literal("true")
_NUMS = (int, float)
_UNEVALUATED = (Arith, Func, Var)


def _univ(left: Term, right: Term, b: dict, trail: list) -> bool:
    """``p(1,2)[a] =.. [default, p, [1,2], [a]]`` (Jason 3; a 3-element list is accepted)."""
    if isinstance(left, Literal):
        annots = make_list(left.annots or ())
        ns, name = split_ns(left.functor)
        functor = Literal(("~" if left.neg else "") + name)
        lst = make_list([DEFAULT_NS if ns == DEFAULT_NS.functor else Literal(ns), functor, make_list(left.args),
                         annots])
        if is_list(right):
            items = _items(right)
            if items is not None and len(items) == 3:
                lst = make_list([functor, make_list(left.args), annots])
        return unify(lst, right, b, trail)
    parts = left.as_plan_parts() if hasattr(left, "as_plan_parts") and left.plan is not None else None
    if parts is not None:
        # a plan term: [Label, Trigger, Context, Body] (Jason's Plan.getAsListOfTerms; demos/meta-programming)
        plan, term = left.plan, type(left)
        label = plan.label if plan.label is not None and plan.label.functor else plan.ensure_label()
        trigger = term(plan=type(plan)(plan.trigger), bare=True)
        body = term(body=plan.body, bare=True)
        return unify(make_list([label, trigger, plan.context if plan.context is not None else _TRUE_ATOM, body]),
                     right, b, trail)
    if type(left) is Var or type(left) is NsTerm:
        items = _items(right)
        if items is None or len(items) not in (3, 4):
            raise ArithmeticError_(f"=.. needs [Namespace, Functor, Args, Annots], got {to_str(right)}")
        ns = DEFAULT_NS
        if len(items) == 4:
            ns, items = items[0], items[1:]
            if not (isinstance(ns, Literal) and not ns.args):
                raise ArithmeticError_(f"=..: the name space must be an atom, got {to_str(ns)}")
        f, args, annots = items
        if not isinstance(f, Literal):
            raise ArithmeticError_(f"=..: functor must be an atom, got {to_str(f)}")
        name, neg = f.functor, False
        if name.startswith("~"):
            name, neg = name[1:], True
        lit = Literal(in_ns(ns.functor, name), tuple(list_items(args)), tuple(list_items(annots)) or None, neg)
        return unify(left, lit, b, trail)
    return False


def _items(t: Term) -> list | None:
    try:
        return list_items(t)
    except TypeError:
        return None


__all__ = ["solve", "solve_first", "SolveError", "KnowledgeBase", "compare_equal"]


# ---------------------------------------------------------------------- compiled formulas
# Plan contexts and if/while/for conditions are small formulas evaluated millions of times. They
# are compiled once into closures in continuation-passing style: ``fn(kb, b, trail, k)`` calls
# ``k()`` for each solution (bindings in ``b``) and returns True as soon as ``k()`` does; it undoes
# its own bindings when it fails. Literals that have rules fall back to the explicit machine above,
# so deep rule recursion still costs no Python stack.

_COMPILED: dict[int, tuple] = {}
_OLDER: dict[int, tuple] = {}
COMPILED_LIMIT = 4096
"""Formulas kept compiled, by identity (the formula is held so that its id is not reused), in two generations of
at most this many each. The program's own formulas are fixed, but formulas made while the agent runs (a question
asked of it, a condition or query built with bound variables) are new objects each time: kept for ever they grew an
agent by ~3 MiB an hour (issue 22's soak). When the young generation (``_COMPILED``, the one looked up first, also by
``body``) is full it becomes the older one and the oldest goes; a formula found in the older generation moves back
to the young one without being compiled again. So what is used at least once a generation stays compiled, however
many formulas the program has, and a formula made once is dropped after two (at most 2 x 4096 x ~3 KB, 24 MB).
A plain oldest-out cache would have compiled a program of more formulas than the limit again at every use."""


def _true_k() -> bool:
    return True


def compiled(formula: Term):
    key = id(formula)
    entry = _COMPILED.get(key)
    if entry is not None and entry[0] is formula:
        return entry[1]
    entry = _OLDER.get(key)
    fn = entry[1] if entry is not None and entry[0] is formula else _compile(formula)
    if len(_COMPILED) >= COMPILED_LIMIT:   # a new generation, in place (``body`` holds ``_COMPILED`` itself)
        _OLDER.clear()
        _OLDER.update(_COMPILED)
        _COMPILED.clear()
    _COMPILED[key] = (formula, fn)
    return fn


def _compile(f: Term):
    tf = type(f)
    if tf is And:
        if _is_fact_literal(f.left):  # `p(X) & rest`: rest runs per matching belief, no closure made
            return _compile_fact_literal(f.left, _compile(f.right))
        left, right = _compile(f.left), _compile(f.right)

        def conj(kb, b, trail, k):
            return left(kb, b, trail, lambda: right(kb, b, trail, k))
        return conj
    if tf is Or:
        left, right = _compile(f.left), _compile(f.right)

        def disj(kb, b, trail, k):
            return left(kb, b, trail, k) or right(kb, b, trail, k)
        return disj
    if tf is Not:
        inner = _compile(f.arg)

        def negation(kb, b, trail, k):
            mark = len(trail)
            found = inner(kb, b, trail, _true_k)
            undo(b, trail, mark)
            return (not found) and k()
        return negation
    if tf is Rel and f.op in _ORDER_OPS:
        return _compile_order(f)
    if tf is Rel and f.op == "=":
        return _compile_unify(f)
    if tf is Rel:
        def relation(kb, b, trail, k):
            mark = len(trail)
            try:
                ok = _rel(kb, f, b, trail)
            except ArithmeticError_ as exc:
                raise SolveError("wrong_arguments", str(exc)) from None
            if ok and k():
                return True
            undo(b, trail, mark)
            return False
        return relation
    if tf is Literal:
        if not f.args and not f.neg and f.annots is None:
            if f.functor == "true":
                return lambda kb, b, trail, k: k()
            if f.functor == "false":
                return lambda kb, b, trail, k: False
        if "." in f.functor and not f.neg:
            def internal(kb, b, trail, k):
                mark = len(trail)
                for _ in kb.call_internal(f, b, trail):
                    if k():
                        return True
                    undo(b, trail, mark)  # the action's next solution starts from the same bindings
                undo(b, trail, mark)
                return False
            return internal
        return _compile_fact_literal(f, None)
    # variables and anything unusual: the general machine
    def general(kb, b, trail, k):
        for _ in solve(kb, f, b, trail):
            if k():
                return True
        return False
    return general


def _is_fact_literal(f: Term) -> bool:
    """A literal looked up in the belief base (not true/false, not an internal action)."""
    if type(f) is not Literal:
        return False
    if not f.args and not f.neg and f.annots is None and f.functor in ("true", "false"):
        return False
    return not ("." in f.functor and not f.neg)


def _compile_fact_literal(f: Literal, then):
    """A belief-base literal; ``then`` (a compiled formula, or None for the continuation ``k``)
    runs for each matching belief. Literals with rules or annotation variables use the machine."""
    annot_vars = f.annots is not None and _annots_have_vars(f)
    key = (f.neg, f.functor, len(f.args))
    # a first argument that is a variable: while it is free every belief of the key is a candidate
    # (BeliefBase.candidates_by_key without a call), bound it selects by the first-argument index
    first = f.args[0] if f.args and type(f.args[0]) is Var else None
    # `p(X)`: one argument, a variable, no annotations. While X is free, every belief of the key
    # matches (beliefs are ground; annotations of the belief do not matter): X is bound, no unify
    single = first if len(f.args) == 1 and f.annots is None and f.annot_tail is None else None

    # Two bodies on purpose: the last literal of a context calls k directly; routing it through a
    # `then` that calls k would add a Python call per candidate belief in every context (hot path).
    if then is None:
        def literal(kb, b, trail, k):
            bb = kb.bb
            if annot_vars or bb._rules.get(key):  # has_rules, inlined
                for _ in solve(kb, f, b, trail):
                    if k():
                        return True
                return False
            if first is not None and first not in b:
                bucket = bb._facts.get(key)
                found = () if bucket is None else (bucket._sorted or bucket.all())
                if single is not None:
                    mark = len(trail)
                    trail.append(single)
                    for fact in found:
                        a0 = fact.args[0]
                        if type(a0) is Literal and NS_SEP in a0.functor and in_other_ns(a0):
                            continue  # not for a variable of the default name space (unify.in_other_ns)
                        b[single] = a0
                        if k is _true_k or k():
                            return True
                        while len(trail) > mark + 1:
                            b.pop(trail.pop(), None)
                    b.pop(single, None)
                    trail.pop()
                    return False
            else:
                found = bb.candidates_by_key(key, f, b)
            for fact in found:
                mark = len(trail)
                if unify(f, fact, b, trail) and (k is _true_k or k()):
                    return True
                while len(trail) > mark:  # undo, inlined
                    b.pop(trail.pop(), None)
            return False
        return literal

    def literal_then(kb, b, trail, k):
        bb = kb.bb
        if annot_vars or bb._rules.get(key):  # has_rules, inlined
            for _ in solve(kb, f, b, trail):
                if then(kb, b, trail, k):
                    return True
            return False
        if first is not None and first not in b:
            bucket = bb._facts.get(key)
            found = () if bucket is None else (bucket._sorted or bucket.all())
            if single is not None:
                mark = len(trail)
                trail.append(single)
                for fact in found:
                    a0 = fact.args[0]
                    if type(a0) is Literal and NS_SEP in a0.functor and in_other_ns(a0):
                        continue  # not for a variable of the default name space (unify.in_other_ns)
                    b[single] = a0
                    if then(kb, b, trail, k):
                        return True
                    while len(trail) > mark + 1:
                        b.pop(trail.pop(), None)
                b.pop(single, None)
                trail.pop()
                return False
        else:
            found = bb.candidates_by_key(key, f, b)
        for fact in found:
            mark = len(trail)
            if unify(f, fact, b, trail) and then(kb, b, trail, k):
                return True
            while len(trail) > mark:  # undo, inlined
                b.pop(trail.pop(), None)
        return False
    return literal_then


_ORDER_OPS = {"<": operator.lt, ">": operator.gt, "<=": operator.le, ">=": operator.ge}


def _compile_order(f: Rel):
    """``<`` ``>`` ``<=`` ``>=``: numbers compared at once (no bindings to undo); others via ``_rel``."""
    cmp = _ORDER_OPS[f.op]
    left0, right0 = f.left, f.right

    def order(kb, b, trail, k):
        x = left0
        while type(x) is Var:
            v = b.get(x)
            if v is None:
                break
            x = v
        tx = type(x)
        if tx is not int and tx is not float:
            x = resolve(x, b)
            tx = type(x)
        y = right0
        while type(y) is Var:
            v = b.get(y)
            if v is None:
                break
            y = v
        ty = type(y)
        if ty is not int and ty is not float:
            y = resolve(y, b)
            ty = type(y)
        if (tx is int or tx is float) and (ty is int or ty is float):
            return cmp(x, y) and (k is _true_k or k())
        try:
            ok = _rel(kb, f, b, trail)
        except ArithmeticError_ as exc:
            raise SolveError("wrong_arguments", str(exc)) from None
        return ok and k()
    return order


def _compile_unify(f: Rel):
    """``X = expr``: both sides resolved (arithmetic evaluated), then unified."""
    left0, right0 = f.left, f.right
    # `X = A op B` with an integer operator: the sum of two integers without a resolve call
    int_op = INT_OPS.get(right0.op) if type(right0) is Arith and right0.right is not None else None
    op_left = right0.left if int_op is not None else None
    op_right = right0.right if int_op is not None else None

    def unify_rel(kb, b, trail, k):
        mark = len(trail)
        x = left0
        while type(x) is Var:  # deref, inlined
            v = b.get(x)
            if v is None:
                break
            x = v
        if type(x) is not int and type(x) is not float and type(x) is not Var:
            try:
                x = resolve(x, b)
            except ArithmeticError_ as exc:
                raise SolveError("wrong_arguments", str(exc)) from None
        y = None
        if int_op is not None:
            p, q = op_left, op_right
            if type(p) is Var:
                p = b.get(p, p)
            if type(q) is Var:
                q = b.get(q, q)
            if type(p) is int and type(q) is int and type(x) is not Func:
                r = int_op(p, q)
                if -_EXACT < r < _EXACT:
                    y = r
        if y is None:
            y = right0
            if type(y) is Var:
                y = deref(y, b)
            if type(y) is not int and type(y) is not float and type(y) is not Var:
                try:
                    y = resolve(y, b)
                except ArithmeticError_ as exc:
                    raise SolveError("wrong_arguments", str(exc)) from None
                if type(y) is Func or type(x) is Func:
                    raise SolveError("wrong_arguments", f"{to_str(f, b)}: a function argument is unbound")
        ty = type(y)
        # `X = value` with X free: bind, no unify call (unless the value's name space is to be looked at)
        if type(x) is Var and ty is not Var and ty is not NsTerm and (ty is not Literal or NS_SEP not in y.functor):
            b[x] = y
            trail.append(x)
            if k is _true_k or k():
                return True
            undo(b, trail, mark)
            return False
        if unify(x, y, b, trail) and k():
            return True
        undo(b, trail, mark)
        return False
    return unify_rel


def solve_first_compiled(kb: KnowledgeBase, formula: Term, b: dict) -> bool:
    """One solution of ``formula`` (bindings kept in ``b``), through the compiled closure."""
    return compiled(formula)(kb, b, [], _true_k)
