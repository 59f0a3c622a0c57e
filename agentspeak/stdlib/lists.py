"""List actions: member, length, concat (also strings), nth, reverse, delete, sort, max, min, sum..."""
from __future__ import annotations

import random as _random

from agentspeak.stdlib.registry import IAError, internal_action, wrong_arguments
from agentspeak.terms import (
    NIL, SortKey, compare, is_list, list_items, make_list, normalise_number, to_str,
)


def items_of(t, action: str) -> list:
    try:
        return list_items(t)
    except TypeError:
        raise wrong_arguments(f"{action}: '{to_str(t)}' is not a list") from None


@internal_action(".member", args=2)
def member(ctx, x, lst):
    """Backtracks over the elements of ``lst`` that unify with ``x``."""
    for item in items_of(lst, ".member"):
        mark = len(ctx.trail)
        if ctx.unify(x, item):
            yield
            from agentspeak.unify import undo
            undo(ctx.b, ctx.trail, mark)


@internal_action(".length", args=2)
def length(ctx, x, n):
    """Length of a list or a string."""
    if isinstance(x, str):
        return ctx.unify(n, len(x))
    return ctx.unify(n, len(items_of(x, ".length")))


@internal_action(".concat", args=(2, None))
def concat(ctx, *args):
    """Concatenate lists (or strings: any non-list argument is turned into its text)."""
    *parts, result = args
    if all(is_list(p) for p in parts):
        out: list = []
        for p in parts:
            out.extend(items_of(p, ".concat"))
        return ctx.unify(result, make_list(out))
    return ctx.unify(result, "".join(p if isinstance(p, str) else to_str(p) for p in parts))


@internal_action(".nth", args=3)
def nth(ctx, index, lst, x):
    """The element at 0-based ``index`` (backtracks over positions if ``index`` is unbound)."""
    seq = list(lst) if isinstance(lst, str) else items_of(lst, ".nth")
    if isinstance(index, (int, float)):
        i = int(index)
        if not 0 <= i < len(seq):
            raise IAError("ia_failed", f".nth: index {i} out of range 0..{len(seq) - 1}")
        yield from _yield_if(ctx, x, seq[i])
        return
    from agentspeak.unify import undo
    for i, item in enumerate(seq):
        mark = len(ctx.trail)
        if ctx.unify(index, i) and ctx.unify(x, item):
            yield
        undo(ctx.b, ctx.trail, mark)


def _yield_if(ctx, a, c):
    if ctx.unify(a, c):
        yield


@internal_action(".reverse", args=2)
def reverse(ctx, lst, result):
    """Reverse a list or a string."""
    if isinstance(lst, str):
        return ctx.unify(result, lst[::-1])
    return ctx.unify(result, make_list(list(reversed(items_of(lst, ".reverse")))))


@internal_action(".delete", args=(3, 4))
def delete(ctx, *args):
    """``.delete(X, L, R)``: remove every element unifying with X; a number X is an index (Jason)."""
    from agentspeak.unify import unifies
    if len(args) == 4:
        start, end, lst, result = args
        seq = items_of(lst, ".delete")
        return ctx.unify(result, make_list(seq[: int(start)] + seq[int(end):]))
    x, lst, result = args
    if isinstance(lst, str):
        return ctx.unify(result, lst.replace(x if isinstance(x, str) else to_str(x), ""))
    seq = items_of(lst, ".delete")
    if isinstance(x, (int, float)) and not isinstance(x, bool):
        i = int(x)
        return ctx.unify(result, make_list(seq[:i] + seq[i + 1:]))
    return ctx.unify(result, make_list([e for e in seq if not unifies(x, e, dict(ctx.b))]))


@internal_action(".sort", args=2)
def sort(ctx, lst, result):
    """Sort by the standard order of terms (duplicates kept)."""
    return ctx.unify(result, make_list(sorted(items_of(lst, ".sort"), key=SortKey)))


@internal_action(".max", args=2)
def max_(ctx, lst, result):
    """Greatest element by the standard order of terms (fails on an empty list)."""
    seq = items_of(lst, ".max")
    return bool(seq) and ctx.unify(result, max(seq, key=SortKey))


@internal_action(".min", args=2)
def min_(ctx, lst, result):
    """Smallest element by the standard order of terms (fails on an empty list)."""
    seq = items_of(lst, ".min")
    return bool(seq) and ctx.unify(result, min(seq, key=SortKey))


@internal_action(".sum", args=2)
def sum_(ctx, lst, result):
    """Sum of a list of numbers."""
    seq = items_of(lst, ".sum")
    if not all(isinstance(e, (int, float)) for e in seq):
        raise wrong_arguments(".sum needs a list of numbers")
    return ctx.unify(result, normalise_number(sum(seq)))


@internal_action(".empty", args=1)
def empty(ctx, lst):
    """True for ``[]`` and ``""``."""
    return lst is NIL or lst == ""


@internal_action(".shuffle", args=2)
def shuffle(ctx, lst, result):
    seq = items_of(lst, ".shuffle")
    ctx.agent.random.shuffle(seq) if hasattr(ctx.agent, "random") else _random.shuffle(seq)
    return ctx.unify(result, make_list(seq))


def _set(seq) -> list:
    out: list = []
    for e in sorted(seq, key=SortKey):
        if not out or compare(out[-1], e) != 0:
            out.append(e)
    return out


@internal_action(".union", args=3)
def union(ctx, a, b, result):
    return ctx.unify(result, make_list(_set(items_of(a, ".union") + items_of(b, ".union"))))


@internal_action(".intersection", args=3)
def intersection(ctx, a, b, result):
    bs = items_of(b, ".intersection")
    return ctx.unify(result, make_list(_set(e for e in items_of(a, ".intersection") if e in bs)))


@internal_action(".difference", args=3)
def difference(ctx, a, b, result):
    bs = items_of(b, ".difference")
    return ctx.unify(result, make_list(_set(e for e in items_of(a, ".difference") if e not in bs)))


@internal_action(".range", args=(3, 4))
def range_(ctx, x, start, end, step=1):
    """Backtrack over the integers from ``start`` to ``end`` (inclusive)."""
    from agentspeak.unify import undo
    i = int(start)
    step = int(step)
    if step == 0:
        raise wrong_arguments(".range: step must not be 0")
    while (step > 0 and i <= int(end)) or (step < 0 and i >= int(end)):
        mark = len(ctx.trail)
        if ctx.unify(x, i):
            yield
        undo(ctx.b, ctx.trail, mark)
        i += step


@internal_action(".list", args=1)
def is_list_(ctx, x):
    return is_list(x)


