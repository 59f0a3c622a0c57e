"""String and term actions: term2string, string, substring, lower/upper case, replace, type tests."""
from __future__ import annotations

from agentspeak.stdlib.registry import IAError, internal_action, wrong_arguments
from agentspeak.terms import Literal, Var, is_ground, is_list, to_print_str, to_str
from agentspeak.unify import undo


@internal_action(".term2string", args=2)
def term2string(ctx, term, text):
    """Term to its text, or text parsed into a term."""
    if not isinstance(term, Var):
        return ctx.unify(text, to_str(term) if not isinstance(term, str) else term)
    if not isinstance(text, str):
        raise wrong_arguments(".term2string needs a term or a string")
    from agentspeak.parser import parse_term
    return ctx.unify(term, parse_term(text))


@internal_action(".string", args=1)
def string(ctx, x):
    return isinstance(x, str)


@internal_action(".atom", args=1)
def atom_(ctx, x):
    return isinstance(x, Literal) and not x.args and not x.annots and not x.neg


@internal_action(".number", args=1)
def number(ctx, x):
    return isinstance(x, (int, float)) and not isinstance(x, bool)


@internal_action(".literal", args=1)
def literal(ctx, x):
    return isinstance(x, Literal)


@internal_action(".structure", args=1)
def structure(ctx, x):
    return isinstance(x, Literal) or is_list(x)


@internal_action(".ground", args=1)
def ground(ctx, x):
    return is_ground(x)


@internal_action(".internal_action", args=1)
def internal_action_(ctx, x):
    """Is ``x`` an internal action term (``.print(a)``, ``kk.tt(1)``: a functor with a dot)? A
    registered arithmetic function (``math.abs(1)``) is not, as in Jason."""
    return isinstance(x, Literal) and "." in x.functor and not x.functor.startswith("'")


@internal_action(".substring", args=(2, 4))
def substring(ctx, sub, text, pos=None, end=None):
    """Is ``sub`` in ``text``? With a third argument, backtracks over the positions (and a fourth, the
    position of the last character). ``.substring(R, Text, Start[, End])`` with R unbound gives the
    substring from Start (Jason 3's forms, including its reversed-argument compatibility form)."""
    s = sub if isinstance(sub, str) else to_str(sub)
    t = text if isinstance(text, str) else to_str(text)
    if pos is None:  # not a generator here: a function with ``yield`` would always fail
        return s in t
    if isinstance(pos, int) and isinstance(sub, Var):
        stop = end if isinstance(end, int) else len(t)
        return _slice(ctx, sub, t, pos, stop)
    if isinstance(pos, int) and isinstance(text, Var):
        stop = end if isinstance(end, int) else len(s)
        return _slice(ctx, text, s, pos, stop)
    return _positions(ctx, s, t, pos, end)


def _slice(ctx, var, t: str, start: int, stop: int) -> bool:
    if not (0 <= start <= stop <= len(t)):
        raise IAError("wrong_arguments", f".substring: positions {start}..{stop} outside \"{t}\"")
    return ctx.unify(var, t[start:stop])


def _positions(ctx, s: str, t: str, pos, end=None):
    start = t.find(s)
    while start >= 0:
        mark = len(ctx.trail)
        if ctx.unify(pos, start) and (end is None or ctx.unify(end, start - 1 + len(s))):
            yield
        undo(ctx.b, ctx.trail, mark)
        start = t.find(s, start + 1)


@internal_action(".lower_case", args=2)
def lower_case(ctx, text, result):
    return ctx.unify(result, to_print_str(text).lower())


@internal_action(".upper_case", args=2)
def upper_case(ctx, text, result):
    return ctx.unify(result, to_print_str(text).upper())


@internal_action(".replace", args=4)
def replace(ctx, text, old, new, result):
    return ctx.unify(result, to_print_str(text).replace(to_print_str(old), to_print_str(new)))


@internal_action(".add_annot", args=3)
def add_annot(ctx, lit, annot, result):
    if not isinstance(lit, Literal):
        raise wrong_arguments(".add_annot needs a literal")
    return ctx.unify(result, lit.add_annot(annot))
