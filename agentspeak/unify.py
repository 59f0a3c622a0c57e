"""Unification with Jason's annotation semantics.

``unify(a, b, bindings, trail)`` binds variables in ``bindings`` (recording each bound variable
in ``trail`` so the caller can undo) and returns True or False. On False the caller must undo the
trail: the bindings may be half made. Annotations are directional: every annotation of the left
term must unify with one of the right term's (``p[a] = p[a,b]`` succeeds, ``p[a,b] = p[a]`` fails),
which is how Jason matches plan triggers (left) against events and queries (left) against beliefs.
Lists are walked along their tails in a loop, so long lists cost no Python recursion.
"""
from __future__ import annotations

from typing import Iterator

from agentspeak.terms import (
    DEFAULT_NS_NAME, LOCAL_NS_PREFIX, NIL, NS_SEP, And, AnnotatedVar, Arith, Bindings, Cons, Func, Literal, Not, NsTerm, Or,
    Rel, Term, Var, deref, list_items, make_list, ns_atom, split_ns,
)


def bind(v: Var, t: Term, b: Bindings, trail: list) -> None:
    b[v] = t
    trail.append(v)


def undo(b: Bindings, trail: list, mark: int) -> None:
    """Remove the bindings made since ``mark`` (a previous ``len(trail)``)."""
    while len(trail) > mark:
        b.pop(trail.pop(), None)


def unify(a: Term, c: Term, b: Bindings, trail: list) -> bool:
    if type(a) is Literal and type(c) is Literal and a.annots is None and a.annot_tail is None:
        # fast path for the most common case: a plan trigger or a query against a belief
        if a.functor != c.functor or a.neg != c.neg or len(a.args) != len(c.args):
            return False
        for x, y in zip(a.args, c.args):
            tx = type(x)
            if tx is Var:
                v = b.get(x)
                if v is None:
                    ty = type(y)
                    # a variable, or a value whose name space must be looked at (NS_SEP: see in_other_ns)
                    if ty is Var or ty is NsTerm or (ty is Literal and NS_SEP in y.functor):
                        if not _unify_general(x, y, b, trail):
                            return False
                        continue
                    b[x] = y
                    trail.append(x)
                    continue
                x = v
                tx = type(x)
            ty = type(y)
            if (tx is int or tx is float) and (ty is int or ty is float):
                if x != y:
                    return False
                continue
            if tx is str and ty is str:
                if x != y:
                    return False
                continue
            if not _unify_general(x, y, b, trail):
                return False
        return True
    return _unify_general(a, c, b, trail)


def _unify_general(a: Term, c: Term, b: Bindings, trail: list) -> bool:
    stack = [(a, c)]
    pop = stack.pop
    push = stack.append
    while stack:
        x, y = pop()
        # dereference both sides
        while type(x) is Var:
            v = b.get(x)
            if v is None:
                break
            x = v
        while type(y) is Var:
            v = b.get(y)
            if v is None:
                break
            y = v
        if x is y:
            continue
        tx, ty = type(x), type(y)
        if tx is Var:
            if ty is Literal:
                if NS_SEP in y.functor and in_other_ns(y):
                    return False
            elif ty is NsTerm:
                if not _unify_var_ns_term(x, y, b, trail):
                    return False
                continue
            b[x] = y
            trail.append(x)
            continue
        if ty is Var:
            if tx is Literal:
                if NS_SEP in x.functor and in_other_ns(x):
                    return False
            elif tx is NsTerm:
                if not _unify_var_ns_term(y, x, b, trail):
                    return False
                continue
            b[y] = x
            trail.append(y)
            continue
        if tx is AnnotatedVar or ty is AnnotatedVar:
            if not _unify_annotated_var(x, y, b, trail):
                return False
            continue
        if tx is Literal:
            if ty is not Literal:
                if ty is NsTerm and unify_ns(y, x, b, trail, False):
                    continue
                return False
            if x.functor != y.functor or x.neg != y.neg or len(x.args) != len(y.args):
                return False
            if x.annots is not None or x.annot_tail is not None:
                if not unify_annots(x, y, b, trail):
                    return False
            for pair in zip(x.args, y.args):
                push(pair)
            continue
        if tx is Cons:
            if ty is not Cons:
                return False
            push((x.tail, y.tail))
            push((x.head, y.head))
            continue
        if (tx is int or tx is float) and (ty is int or ty is float):
            if x != y:
                return False
            continue
        if tx is NsTerm or ty is NsTerm:  # a variable name space (never reached by two plain literals)
            if not (unify_ns(x, y, b, trail, True) if tx is NsTerm else unify_ns(y, x, b, trail, False)):
                return False
            continue
        if tx is str or ty is str:
            if tx is not ty or x != y:
                return False
            continue
        if tx is Func or ty is Func:
            from agentspeak.terms import resolve  # a function in a pattern: evaluate when ground
            rx, ry = resolve(x, b), resolve(y, b)
            if type(rx) is Func or type(ry) is Func:
                if not (type(rx) is Func and type(ry) is Func and rx.name == ry.name
                        and len(rx.args) == len(ry.args)):
                    return False
                for pair in zip(rx.args, ry.args):
                    push(pair)
                continue
            push((rx, ry))
            continue
        if tx is Arith or ty is Arith:
            from agentspeak.terms import resolve  # arithmetic in a pattern: evaluate when ground
            rx, ry = resolve(x, b), resolve(y, b)
            if type(rx) is Arith or type(ry) is Arith:
                if not (type(rx) is Arith and type(ry) is Arith and rx.op == ry.op):
                    return False
                push((rx.left, ry.left))
                if rx.right is not None or ry.right is not None:
                    push((rx.right, ry.right))
                continue
            push((rx, ry))
            continue
        if tx is not ty:
            return False
        if tx in (Rel, And, Or):
            if tx is Rel and x.op != y.op:
                return False
            push((x.right, y.right))
            push((x.left, y.left))
            continue
        if tx is Not:
            push((x.arg, y.arg))
            continue
        unifier = getattr(x, "unify_with", None)
        if unifier is not None:
            if not unifier(y, b, trail):
                return False
            continue
        if x != y:
            return False
    return True


def in_other_ns(lit: Literal) -> bool:
    """Is ``lit`` of a name space other than the default one? Then no variable without a name space binds it:
    Jason's parser gives a variable the name space it is written in (the default one, but for a variable
    written as a formula in a module: ``NsTerm``), and ``Unifier.bind`` binds a variable to a literal only
    if their name spaces unify (``X = ns::b`` fails, ``NS::X = ns::b`` binds NS and X). Callers test
    ``NS_SEP in lit.functor`` first, so a literal of the default name space costs one substring test."""
    f = lit.functor
    return NS_SEP in f and f[0] != "'"


def _unify_var_ns_term(v: Var, t: NsTerm, b: Bindings, trail: list) -> bool:
    """A free variable without a name space against ``NS::body`` (Jason's ``bind``: the name spaces unify,
    so ``NS`` becomes ``default``, and the variable takes the body: ``X = NS::b`` binds X to b,
    ``X = ns::Y`` fails)."""
    return unify(t.ns, ns_atom(DEFAULT_NS_NAME), b, trail) and unify(v, t.body, b, trail)


def unify_ns(x: NsTerm, other: Term, b: Bindings, trail: list, x_left: bool) -> bool:
    """``NS::body = other`` (``x_left``: x is the left side, whose annotations must be a subset). With
    ``other`` a literal, NS unifies with its name space (``default`` when it has none) and the body with
    it without the name space; a variable never takes a local name space (Jason's ``#1priv`` stays in its
    module). A number, string or list unifies with a variable body (Jason: ``ns::A = 10``)."""
    def pair(p, q):
        return unify(p, q, b, trail) if x_left else unify(q, p, b, trail)

    if type(other) is NsTerm:
        return pair(x.ns, other.ns) and pair(x.body, other.body)
    if type(other) is Literal:
        ns_name, name = split_ns(other.functor)
        ns = deref(x.ns, b)
        if type(ns) is Var:
            if ns_name.startswith(LOCAL_NS_PREFIX):
                return False
            bind(ns, ns_atom(ns_name), b, trail)
        elif type(ns) is not Literal or ns.args or ns.functor != ns_name:
            return False
        plain = other if name == other.functor else Literal(name, other.args, other.annots, other.neg,
                                                              other.annot_tail)
        return pair(x.body, plain)
    if type(x.body) is Var:
        return pair(x.body, other)
    return False


def _unify_annotated_var(x: Term, y: Term, b: Bindings, trail: list) -> bool:
    """``X[a|T] = p(1)[a,b]`` as Jason: the left side's annotations are a subset of the right side's;
    the variable is bound to the literal without annotations (``X = p(1)``, ``T = [b]``)."""
    av = x if type(x) is AnnotatedVar else y
    other = y if av is x else x
    if type(other) is AnnotatedVar:  # two annotated variables: unify the variables and the annotations
        return (unify(av.var, other.var, b, trail)
                and unify(make_list(list(x.annots), x.annot_tail), make_list(list(y.annots), y.annot_tail), b, trail))
    if type(other) is not Literal:
        return False
    pattern = av.as_pattern(other.functor, other.args, other.neg)
    if av is x:
        if not unify_annots(pattern, other, b, trail):
            return False
    elif not unify_annots(other, pattern, b, trail):
        return False
    value = deref(av.var, b)
    if type(value) is Var:
        if NS_SEP in other.functor and in_other_ns(other):
            return False  # a variable of the default name space (Jason's bind, see in_other_ns)
        bind(value, other.without_annots(), b, trail)
        return True
    return unify(value, other, b, trail) if av is x else unify(other, value, b, trail)


def unify_annots(x: Literal, y: Literal, b: Bindings, trail: list) -> bool:
    """Every annotation of ``x`` must unify with some annotation of ``y`` (first match wins).

    If ``x`` has an annotation tail ``|T``, T is bound to the list of ``y``'s annotations that
    were not used.
    """
    yann = list(y.annots or ())
    if y.annot_tail is not None:
        tail_value = b.get(y.annot_tail)
        if tail_value is not None:
            yann.extend(_safe_items(tail_value, b))
    used = [False] * len(yann)
    # an unbound tail on the right takes the left annotations it lacks (Jason: p[a,b] = X[H|T], T = [b])
    open_tail = y.annot_tail if y.annot_tail is not None and b.get(y.annot_tail) is None else None
    extra: list = []
    for ax in x.annots or ():
        for i, ay in enumerate(yann):
            if used[i]:
                continue
            mark = len(trail)
            if unify(ax, ay, b, trail):
                used[i] = True
                break
            undo(b, trail, mark)
        else:
            if open_tail is None:
                return False
            extra.append(ax)
    if open_tail is not None and x.annot_tail is None:
        if not unify(open_tail, make_list(extra), b, trail):
            return False
    elif extra:
        return False
    if x.annot_tail is not None:
        rest = make_list([a for a, u in zip(yann, used) if not u])
        return unify(x.annot_tail, rest, b, trail)
    return True


def _safe_items(t: Term, b: Bindings) -> list:
    from agentspeak.terms import resolve
    try:
        return list_items(resolve(t, b))
    except TypeError:
        return []


def unify_annots_all(x: Literal, y: Literal, b: Bindings, trail: list) -> Iterator[None]:
    """Like the annotation part of ``unify`` but backtracking over every way to match.

    Used when a query such as ``b[source(S)]`` must enumerate each source of one belief.
    Each yield leaves the bindings of one solution in ``b``; the caller undoes.
    """
    xann = list(x.annots or ())
    yann = list(y.annots or ())

    def match(i: int, used: frozenset) -> Iterator[None]:
        if i == len(xann):
            if x.annot_tail is not None:
                mark = len(trail)
                rest = make_list([a for k, a in enumerate(yann) if k not in used])
                if unify(x.annot_tail, rest, b, trail):
                    yield
                undo(b, trail, mark)
            else:
                yield
            return
        for k, ay in enumerate(yann):
            if k in used:
                continue
            mark = len(trail)
            if unify(xann[i], ay, b, trail):
                yield from match(i + 1, used | {k})
            undo(b, trail, mark)

    return match(0, frozenset())


def unifies(a: Term, c: Term, b: Bindings | None = None) -> bool:
    """Convenience: do ``a`` and ``c`` unify (bindings kept in ``b`` if given)?"""
    b = {} if b is None else b
    trail: list = []
    if unify(a, c, b, trail):
        return True
    undo(b, trail, 0)
    return False


__all__ = ["bind", "undo", "unify", "unify_annots", "unify_annots_all", "unifies", "NIL"]
