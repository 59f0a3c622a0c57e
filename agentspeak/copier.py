"""Fresh copies of rules, compiled once per rule.

Every call of a rule needs its head and body with brand-new variables (renaming apart). Walking the
rule with ``terms.rename`` copies every node on every call, even ground ones. Here a rule is compiled
once into a small Python function that builds only what holds variables, shares every ground subterm,
and makes each fresh variable once: on fib, renaming was a third of the run time.
Terms the compiler does not know (plan terms, other extension nodes) fall back to ``terms.rename``.
"""
from __future__ import annotations

from typing import Callable

from agentspeak.terms import NIL, And, Arith, Cons, Func, Literal, Not, Or, Rel, Term, Var, rename, variables

Copier = Callable[[], tuple]


class _Unknown(Exception):
    """A node the compiler does not handle: use the generic renaming."""


def _new_literal(functor: str, args: tuple, annots: tuple | None, neg: bool, tail: Var | None) -> Literal:
    """A Literal whose annotations are taken as they are (a renamed copy keeps its source order)."""
    lit = Literal.__new__(Literal)
    lit.functor, lit.args, lit.annots, lit.neg, lit.annot_tail, lit._hash = functor, args, annots, neg, tail, None
    return lit


class _Builder:
    def __init__(self, varnames: dict[Var, str]) -> None:
        self.varnames = varnames
        self.consts: list = []

    def const(self, t: Term) -> str:
        self.consts.append(t)
        return f"c{len(self.consts) - 1}"

    def expr(self, t: Term) -> str:
        tt = type(t)
        if tt is Var:
            return self.varnames[t]
        if tt is int or tt is float or tt is str or t is NIL or tt is bool:
            return self.const(t)
        if not variables(t):
            return self.const(t)  # ground: shared, never copied
        if tt is Literal:
            args = "(" + "".join(self.expr(a) + "," for a in t.args) + ")"
            if t.annots is None and t.annot_tail is None:
                return f"L({self.const(t.functor)},{args},None,{t.neg},None)"
            annots = "(" + "".join(self.expr(a) + "," for a in t.annots) + ")" if t.annots else "None"
            tail = self.expr(t.annot_tail) if t.annot_tail is not None else "None"
            return f"L({self.const(t.functor)},{args},{annots},{t.neg},{tail})"
        if tt is Cons:
            heads = []
            cur: Term = t
            while type(cur) is Cons:
                heads.append(self.expr(cur.head))
                cur = cur.tail
            out = self.expr(cur)
            for h in reversed(heads):
                out = f"C({h},{out})"
            return out
        if tt is Arith:
            right = self.expr(t.right) if t.right is not None else "None"
            return f"A({self.const(t.op)},{self.expr(t.left)},{right})"
        if tt is Rel:
            return f"R({self.const(t.op)},{self.expr(t.left)},{self.expr(t.right)})"
        if tt is And:
            return f"An({self.expr(t.left)},{self.expr(t.right)})"
        if tt is Or:
            return f"O({self.expr(t.left)},{self.expr(t.right)})"
        if tt is Not:
            return f"N({self.expr(t.arg)})"
        if tt is Func:
            args = "(" + "".join(self.expr(a) + "," for a in t.args) + ")"
            return f"F({self.const(t.name)},{args},{self.const(t.spec)})"
        raise _Unknown


def compile_copier(terms: tuple) -> Copier:
    """A function returning a copy of ``terms`` (a tuple) with fresh variables, consistent across them."""
    vs: list = []
    for t in terms:
        variables(t, vs)
    varnames = {v: f"v{i}" for i, v in enumerate(vs)}
    builder = _Builder(varnames)
    try:
        exprs = [builder.expr(t) for t in terms]
    except (_Unknown, RecursionError):
        def generic() -> tuple:
            mapping: dict = {}
            return tuple(rename(t, mapping) for t in terms)
        return generic
    names = {f"c{i}": c for i, c in enumerate(builder.consts)}
    names.update(V=Var, L=_new_literal, C=Cons, A=Arith, R=Rel, An=And, O=Or, N=Not, F=Func)
    names.update({f"n{i}": v.name for i, v in enumerate(vs)})
    fresh = "".join(f"    v{i} = V(n{i})\n" for i in range(len(vs)))
    source = f"def copy():\n{fresh}    return ({''.join(e + ',' for e in exprs)})\n"
    namespace: dict = {}
    exec(compile(source, "<rule copier>", "exec"), names, namespace)  # noqa: S102 - code built above
    return namespace["copy"]


def rule_copier(rule) -> Copier:
    """The compiled copier of ``rule`` (head, body), kept on the rule itself."""
    fn = rule.__dict__.get("_copier")
    if fn is None:
        fn = rule.__dict__["_copier"] = compile_copier((rule.head, rule.body))
    return fn
