"""How deeply a parsed clause nests, measured without recursion, so that input nested too deeply is
refused with a located error before the interpreter walks it.

Why: the interpreter's functions (``resolve``, ``unify``, ``to_str`` ...) recurse once per nesting
level. Run from source that ends in a ``RecursionError``; compiled by Cython (``agentspeak/_speedups.py``)
the same recursion has no such guard and overflows the C stack: the process dies with SIGSEGV and no
log line. One message whose content nests ``f(f(f(...)))`` 20,000 deep was enough to kill any agent.
So every parse (program files, message contents, ``.add_plan`` strings, ``tellHow`` plans) measures
its clauses here, and the hand-written reader of message contents (``ground_terms``) stops at the
same depth. A list's elements are one level below the list however long it is (``[1,2,...]`` is a
chain of cells, walked in a loop everywhere), so long flat lists stay allowed.

This module is never compiled (it guards the compiled ones) and imports nothing of the interpreter.
"""
from __future__ import annotations

import re

#: The deepest nesting a clause may have: far beyond hand-written AgentSpeak (Jason programs rarely
#: nest ten levels), far below what the interpreter can walk run from source (Python's recursion
#: limit, 1,000 frames, with the reasoning cycle's own frames below) or compiled (the C stack).
MAX_NESTING = 200

_LEAVES = (int, float, str, bool, bytes, type(None))


def nesting_depth(value: object, limit: int = MAX_NESTING) -> int:
    """The nesting depth of ``value`` (a term, a plan, a rule, a tuple of them), counted up to just
    past ``limit`` (the walk stops there: a hostile input costs no more than a legal one)."""
    deepest = 0
    stack: list[tuple[object, int]] = [(value, 0)]
    pop, push = stack.pop, stack.append
    reached: dict[int, int] = {}  # a shared subterm is walked again only when reached deeper
    while stack:
        node, depth = pop()
        if isinstance(node, _LEAVES):
            continue
        if reached.get(id(node), -1) >= depth:
            continue
        reached[id(node)] = depth
        if depth > deepest:
            deepest = depth
            if deepest > limit:
                return deepest
        if isinstance(node, (tuple, list, frozenset, set)):
            for item in node:  # a container is not a level of its own (a plan body is a tuple)
                push((item, depth))
            continue
        if isinstance(node, dict):
            for item in node.values():
                push((item, depth))
            continue
        tail = getattr(node, "tail", None)
        head = getattr(node, "head", None)
        if type(node).__name__ == "Cons":  # a list cell: the elements below, the rest of the list beside
            push((head, depth + 1))
            push((tail, depth))
            continue
        for child in _children(node):
            push((child, depth + 1))
    return deepest


def _children(node: object) -> list:
    """The attribute values of an interpreter object (its ``__slots__`` along the MRO and its ``__dict__``)."""
    out = []
    for cls in type(node).__mro__:
        slots = cls.__dict__.get("__slots__", ())
        for name in (slots,) if isinstance(slots, str) else slots:
            if name.startswith("__") or name == "_hash":
                continue
            value = getattr(node, name, None)
            if value is not None and not isinstance(value, _LEAVES):
                out.append(value)
    attributes = getattr(node, "__dict__", None)
    if attributes:
        out.extend(v for v in attributes.values() if v is not None and not isinstance(v, _LEAVES))
    if not out:  # a compiled C type (``Trigger``, say) shows neither: its fields by name
        for name in _FIELDS:
            value = getattr(node, name, None)
            if value is not None and not isinstance(value, _LEAVES) and not callable(value):
                out.append(value)
    return out


_FIELDS = ("literal", "trigger", "context", "body", "head", "term", "args", "annots", "annot_tail",
           "left", "right", "arg", "content")


# brackets, and what may hold brackets that do not count: strings, quoted atoms, comments
_BRACKETS = re.compile(r"""[(\[{]|[)\]}]|"(?:[^"\\\n]|\\.)*"|'[^'\n]*'|//[^\n]*|/\*.*?\*/""", re.S)


def first_too_deep_bracket(text: str, limit: int = MAX_NESTING) -> int | None:
    """The offset of the first bracket nested deeper than ``limit`` in source text, else None: a scan
    at regular-expression speed before the parser spends seconds on 20,000 nested brackets."""
    if text.count("(") + text.count("[") + text.count("{") <= limit:
        return None
    depth = 0
    for match in _BRACKETS.finditer(text):
        char = match.group()[0]
        if char in "([{":
            depth += 1
            if depth > limit:
                return match.start()
        elif char in ")]}":
            depth -= 1
    return None


def too_deep_message(limit: int = MAX_NESTING) -> str:
    return f"nested too deeply: more than {limit} levels of terms, lists, expressions or blocks"
