"""Jason's mutable collections held by a variable: ``.set.*`` (a sorted set), ``.map.*`` (a map sorted by
key) and ``.queue.*`` (FIFO, or sorted with ``priority``). As in Jason 3, ``.set.add(S, a)`` changes the
set S is bound to; ``.member``, ``.length`` and ``for`` loops see a set or a queue as the list of its
elements (``agentspeak.terms.list_items``). A set prints ``{a,b}``, a map ``{k->v}``, a queue as a list.
"""
from __future__ import annotations

import bisect

from agentspeak.stdlib.registry import internal_action, wrong_arguments
from agentspeak.terms import Literal, SortKey, Var, list_items, make_list, to_str
from agentspeak.unify import undo


class _Collection:
    """A mutable term: resolving or renaming it gives the object itself (it is shared, as in Jason)."""

    def resolve(self, b, depth: int = 0):
        return self

    def rename(self, mapping):
        return self

    def subterms(self) -> list:
        return []

    def unify_with(self, other, b, trail) -> bool:
        return other is self or (type(other) is type(self) and self.items() == other.items())

    def __eq__(self, other) -> bool:
        return other is self or (type(other) is type(self) and self.items() == other.items())

    def __hash__(self) -> int:
        return id(self)

    def __repr__(self) -> str:
        return str(self)


class SetTerm(_Collection):
    def __init__(self, items=()) -> None:
        self.elems: list = []
        for x in items:
            self.add(x)

    def add(self, x) -> None:
        keys = [SortKey(e) for e in self.elems]
        k = SortKey(x)
        i = bisect.bisect_left(keys, k)
        if i < len(self.elems) and self.elems[i] == x:
            return
        self.elems.insert(i, x)

    def items(self) -> list:
        return list(self.elems)

    list_items = items

    def __str__(self) -> str:
        return "{" + ",".join(to_str(e) for e in self.elems) + "}"


class QueueTerm(_Collection):
    def __init__(self, priority: bool = False, items=()) -> None:
        self.priority = priority
        self.elems: list = []
        for x in items:
            self.add(x)

    def add(self, x) -> None:
        if self.priority:
            keys = [SortKey(e) for e in self.elems]
            self.elems.insert(bisect.bisect_right(keys, SortKey(x)), x)
        else:
            self.elems.append(x)

    def items(self) -> list:
        return list(self.elems)

    list_items = items

    def __str__(self) -> str:
        return "[" + ",".join(to_str(e) for e in self.elems) + "]"


class MapTerm(_Collection):
    def __init__(self, pairs=()) -> None:
        self.keys: list = []
        self.values: dict = {}
        for k, v in pairs:
            self.put(k, v)

    def put(self, k, v) -> None:
        if k not in self.values:
            keys = [SortKey(e) for e in self.keys]
            self.keys.insert(bisect.bisect_left(keys, SortKey(k)), k)
        self.values[k] = v

    def remove(self, k):
        if k in self.values:
            self.keys.remove(k)
            return self.values.pop(k)
        return None

    def items(self) -> list:
        return [(k, self.values[k]) for k in self.keys]

    def __str__(self) -> str:
        return "{" + ",".join(f"{to_str(k)}->{to_str(self.values[k])}" for k in self.keys) + "}"


def _the(kind, t, action: str, ctx=None):
    """The collection an argument is bound to; an unbound variable gets a new one (Jason's getSet)."""
    if ctx is not None and isinstance(t, Var):
        made = kind()
        ctx.unify(t, made)
        return made
    if not isinstance(t, kind):
        raise wrong_arguments(f"{action}: '{to_str(t)}' is not a {kind.__name__[:-4].lower()}")
    return t


def _items(t, action: str) -> list:
    try:
        return list_items(t)
    except TypeError:
        raise wrong_arguments(f"{action}: '{to_str(t)}' is not a list") from None


def _each(ctx, pattern, values):
    for v in values:
        mark = len(ctx.trail)
        if ctx.unify(pattern, v):
            yield
        undo(ctx.b, ctx.trail, mark)


# ---------------------------------------------------------------------- .set
@internal_action(".set.create", args=(1, 2))
def set_create(ctx, s, items=None):
    """``.set.create(S[, List])``: S is a new (sorted) set."""
    return ctx.unify(s, SetTerm(_items(items, ".set.create") if items is not None else ()))


@internal_action(".set.add", args=2)
def set_add(ctx, s, x):
    _the(SetTerm, s, ".set.add", ctx).add(x)


@internal_action(".set.add_all", args=2)
def set_add_all(ctx, s, xs):
    target = _the(SetTerm, s, ".set.add_all", ctx)
    for x in _items(xs, ".set.add_all"):
        target.add(x)


@internal_action(".set.remove", args=2)
def set_remove(ctx, s, x):
    target = _the(SetTerm, s, ".set.remove")
    if x in target.elems:
        target.elems.remove(x)


@internal_action(".set.clear", args=1)
def set_clear(ctx, s):
    _the(SetTerm, s, ".set.clear").elems.clear()


@internal_action(".set.copy", args=2)
def set_copy(ctx, s, result):
    return ctx.unify(result, SetTerm(_the(SetTerm, s, ".set.copy").elems))


@internal_action(".set.union", args=2)
def set_union(ctx, s, other):
    """``.set.union(S, T)``: S gets T's elements too (T a set or a list)."""
    target = _the(SetTerm, s, ".set.union", ctx)
    for x in _items(other, ".set.union"):
        target.add(x)


@internal_action(".set.intersection", args=2)
def set_intersection(ctx, s, other):
    target = _the(SetTerm, s, ".set.intersection")
    keep = _items(other, ".set.intersection")
    target.elems[:] = [x for x in target.elems if x in keep]


@internal_action(".set.difference", args=2)
def set_difference(ctx, s, other):
    target = _the(SetTerm, s, ".set.difference")
    drop = _items(other, ".set.difference")
    target.elems[:] = [x for x in target.elems if x not in drop]


@internal_action(".set.to_list", args=2)
def set_to_list(ctx, s, result):
    return ctx.unify(result, make_list(_the(SetTerm, s, ".set.to_list").items()))


# ---------------------------------------------------------------------- .queue
@internal_action(".queue.create", args=(1, 2))
def queue_create(ctx, q, kind=None):
    """``.queue.create(Q[, priority])``: a FIFO queue, or one kept sorted."""
    priority = isinstance(kind, Literal) and kind.functor == "priority"
    return ctx.unify(q, QueueTerm(priority))


@internal_action(".queue.add", args=2)
def queue_add(ctx, q, x):
    _the(QueueTerm, q, ".queue.add", ctx).add(x)


@internal_action(".queue.add_all", args=2)
def queue_add_all(ctx, q, xs):
    target = _the(QueueTerm, q, ".queue.add_all", ctx)
    for x in _items(xs, ".queue.add_all"):
        target.add(x)


@internal_action(".queue.head", args=2)
def queue_head(ctx, q, x):
    """``.queue.head(Q, H)``: the first element (fails on an empty queue)."""
    elems = _the(QueueTerm, q, ".queue.head").elems
    return bool(elems) and ctx.unify(x, elems[0])


@internal_action(".queue.remove", args=2)
def queue_remove(ctx, q, x):
    """``.queue.remove(Q, H)``: takes the first element out (fails on an empty queue)."""
    elems = _the(QueueTerm, q, ".queue.remove").elems
    return bool(elems) and ctx.unify(x, elems.pop(0))


@internal_action(".queue.clear", args=1)
def queue_clear(ctx, q):
    _the(QueueTerm, q, ".queue.clear").elems.clear()


@internal_action(".queue.copy", args=2)
def queue_copy(ctx, q, result):
    source = _the(QueueTerm, q, ".queue.copy")
    return ctx.unify(result, QueueTerm(source.priority, source.elems))


@internal_action(".queue.to_list", args=2)
def queue_to_list(ctx, q, result):
    return ctx.unify(result, make_list(_the(QueueTerm, q, ".queue.to_list").items()))


# ---------------------------------------------------------------------- .map
@internal_action(".map.create", args=1)
def map_create(ctx, m):
    return ctx.unify(m, MapTerm())


@internal_action(".map.put", args=3)
def map_put(ctx, m, k, v):
    if isinstance(k, Var):
        raise wrong_arguments(".map.put: the key is unbound")
    _the(MapTerm, m, ".map.put", ctx).put(k, v)


@internal_action(".map.get", args=(3, 4))
def map_get(ctx, m, k, v, default=None):
    """``.map.get(M, K, V[, Default])``: the value of K (Default, or failure, when K has none)."""
    values = _the(MapTerm, m, ".map.get").values
    if k in values:
        return ctx.unify(v, values[k])
    return default is not None and ctx.unify(v, default)


@internal_action(".map.remove", args=3)
def map_remove(ctx, m, k, v):
    target = _the(MapTerm, m, ".map.remove")
    if k not in target.values:
        return False
    return ctx.unify(v, target.remove(k))


@internal_action(".map.key", args=2)
def map_key(ctx, m, k):
    """Backtracks over the keys."""
    return _each(ctx, k, list(_the(MapTerm, m, ".map.key").keys))


@internal_action(".map.value", args=2)
def map_value(ctx, m, v):
    """Backtracks over the values."""
    target = _the(MapTerm, m, ".map.value")
    return _each(ctx, v, [target.values[k] for k in target.keys])


@internal_action(".map.clear", args=1)
def map_clear(ctx, m):
    target = _the(MapTerm, m, ".map.clear")
    target.keys.clear()
    target.values.clear()


@internal_action(".map.copy", args=2)
def map_copy(ctx, m, result):
    return ctx.unify(result, MapTerm(_the(MapTerm, m, ".map.copy").items()))
