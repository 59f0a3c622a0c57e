"""A small hand-written reader for ground terms, the usual content of messages.

Lark's parser costs ~75 µs for a term like ``m(12,"abc")``; a message-heavy agent spends most of its
time there. This reader handles only the ground subset (atoms, quoted atoms, numbers incl. negative
ones, strings, structures, ``~`` negation, annotations, lists) and builds exactly what the grammar's
transformer builds. Anything else (variables, operators, keywords, plan terms, comments, a syntax
error) returns ``None`` and the caller uses the full parser, which also gives the error messages.
"""
from __future__ import annotations

import re

from agentspeak.terms import NIL, Cons, Literal, Term

_TOKEN = re.compile(r"""[ \t\r\n]*(?:
      (?P<num>[0-9]+(?:\.[0-9]+)?(?:[eE][+-]?[0-9]+)?)
    | (?P<atom>[a-z][a-zA-Z0-9_]*)
    | (?P<str>"[^"\\\n]*(?:\\.[^"\\\n]*)*")
    | (?P<qatom>'[^'\n]*')
    | (?P<punct>[(),\[\]~|-])
    )""", re.X)

# words the grammar treats as keywords or operators: the full parser decides what they mean
_KEYWORDS = frozenset({"not", "div", "mod", "if", "elif", "else", "for", "while", "begin", "end",
                       "true", "false"})
_MAX_DEPTH = 200


class _NotGround(Exception):
    """Outside the subset this reader handles."""


def _tokens(text: str) -> list[tuple[str, str]]:
    out = []
    match = _TOKEN.match
    pos, end = 0, len(text)
    while True:
        m = match(text, pos)
        if m is None or m.end() == pos:
            if text[pos:].strip():
                raise _NotGround
            return out
        kind = m.lastgroup
        out.append((kind, m.group(kind)))
        pos = m.end()
        if pos >= end:
            return out


def _number(text: str) -> int | float:
    if "." in text or "e" in text or "E" in text:
        value = float(text)
        return int(value) if value.is_integer() and abs(value) < 2 ** 53 else value
    return int(text)


class _Reader:
    __slots__ = ("toks", "i")

    def __init__(self, toks: list) -> None:
        self.toks, self.i = toks, 0

    def peek(self) -> tuple[str, str] | None:
        return self.toks[self.i] if self.i < len(self.toks) else None

    def expect(self, value: str) -> None:
        tok = self.peek()
        if tok is None or tok[0] != "punct" or tok[1] != value:
            raise _NotGround
        self.i += 1

    def term(self, depth: int) -> Term:
        if depth > _MAX_DEPTH:
            raise _NotGround
        tok = self.peek()
        if tok is None:
            raise _NotGround
        kind, value = tok
        self.i += 1
        if kind == "num":
            return self._after_operand(_number(value))
        if kind == "str":  # the grammar unescapes only \n and \" (as Jason does)
            return self._after_operand(value[1:-1].replace("\\n", "\n").replace('\\"', '"'))
        if kind == "atom":
            if value in _KEYWORDS:
                raise _NotGround
            return self._after_operand(self.literal(value, False, depth))
        if kind == "qatom":  # the quotes stay in the name, as the grammar keeps them
            return self._after_operand(self.literal(value, False, depth))
        if value == "~":
            tok = self.peek()
            if tok is None or tok[0] not in ("atom", "qatom") or tok[1] in _KEYWORDS:
                raise _NotGround
            self.i += 1
            name = tok[1]
            return self._after_operand(self.literal(name, True, depth))
        if value == "-":
            tok = self.peek()
            if tok is None or tok[0] != "num":
                raise _NotGround
            self.i += 1
            return self._after_operand(-_number(tok[1]))
        if value == "[":
            return self._after_operand(self.list_(depth))
        raise _NotGround

    def _after_operand(self, t: Term) -> Term:
        """An operand must be followed by a separator or the end (an operator means an expression)."""
        tok = self.peek()
        if tok is not None and (tok[0] != "punct" or tok[1] not in (",", ")", "]")):
            raise _NotGround
        return t

    def items(self, close: str, depth: int) -> list:
        items: list = []
        tok = self.peek()
        if tok is not None and tok == ("punct", close):
            self.i += 1
            return items
        while True:
            items.append(self.term(depth + 1))
            tok = self.peek()
            if tok == ("punct", ","):
                self.i += 1
                continue
            self.expect(close)  # a `|Tail` is not handled here
            return items

    def literal(self, functor: str, neg: bool, depth: int) -> Literal:
        args: tuple = ()
        if self.peek() == ("punct", "("):
            self.i += 1
            args = tuple(self.items(")", depth))
            if not args:
                raise _NotGround  # `p()` is a syntax error: the full parser says so
        annots = None
        if self.peek() == ("punct", "["):
            self.i += 1
            annots = tuple(self.items("]", depth)) or None
        return Literal(functor, args, annots, neg)

    def list_(self, depth: int) -> Term:
        result: Term = NIL
        for item in reversed(self.items("]", depth)):
            result = Cons(item, result)
        return result


# The commonest content, a flat structure such as pos(3,-4.5,"x",a), read left to right: a regular
# expression for the functor and for each number or atom, and str.find for each string (a string of
# a few KB is found at C speed; a character-class pattern walks it char by char, ~5 ns each).
_BLANK = r"[ \t\r\n]*"
_BLANKS = " \t\r\n"
_HEAD = re.compile(_BLANK + r"([a-z][a-zA-Z0-9_]*)" + _BLANK + r"\(" + _BLANK)
_SCALAR = re.compile(r"(?:(-?" + _BLANK + r"[0-9]+(?:\.[0-9]+)?(?:[eE][+-]?[0-9]+)?)"   # a number
                     + r"|([a-z][a-zA-Z0-9_]*))"                                      # or an atom
                     + _BLANK + r"([,)])" + _BLANK)                                   # and what follows
_STRING = re.compile(r'"[^"\\\n]*(?:\\.[^"\\\n]*)*"')  # with escapes: the grammar's string token
_AFTER = re.compile(_BLANK + r"([,)])" + _BLANK)


def _read_flat(text: str) -> Literal | None:
    head = _HEAD.match(text)
    if head is None or head.group(1) in _KEYWORDS:
        return None
    args: list = []
    pos, end = head.end(), len(text)
    while True:
        if text.startswith('"', pos):
            close = text.find('"', pos + 1)
            if close < 0:
                return None
            value = text[pos + 1:close]
            if "\\" in value:  # an escape: the grammar's token decides where the string ends
                m = _STRING.match(text, pos)
                if m is None:
                    return None
                close = m.end() - 1
                value = text[pos + 1:close].replace("\\n", "\n").replace('\\"', '"')  # only these two, as Jason
            elif "\n" in value:
                return None
            args.append(value)
            if close + 2 == end and text[close + 1] == ")":  # the usual end: no blanks to skip
                return Literal(head.group(1), tuple(args))
            after = _AFTER.match(text, close + 1)
            if after is None:
                return None
            separator = after.group(1)
        else:
            m = _SCALAR.match(text, pos)
            if m is None:
                return None
            num, atom, separator = m.groups()
            after = m
            if num:
                args.append(-_number(num[1:].lstrip(_BLANKS)) if num[0] == "-" else _number(num))
            elif atom in _KEYWORDS:
                return None
            else:
                args.append(Literal(atom))
        pos = after.end()
        if separator == ")":
            return Literal(head.group(1), tuple(args)) if pos == end else None


def read_ground_term(text: str) -> Term | None:
    """The ground term written in ``text``, or None when the full parser must decide."""
    try:
        flat = _read_flat(text)
        if flat is not None:
            return flat
        toks = _tokens(text)
        if not toks:
            return None
        reader = _Reader(toks)
        term = reader.term(0)
        if reader.i != len(toks):
            return None
        return term
    except (_NotGround, ValueError, OverflowError):
        return None
