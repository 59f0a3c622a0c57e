"""The belief base: ground literals indexed by (negated, functor, arity) and by first argument, plus rules.

Jason's model: the same literal with different annotations is ONE belief whose annotation sets are
merged; adding a belief that is already there with no new annotation changes nothing (no event);
a belief disappears when its last ``source(...)`` annotation is removed. ``+b`` adds at the start
of its functor's list, ``+>b`` and initial beliefs at the end, so queries see Jason's order.
"""
from __future__ import annotations

import itertools
from typing import Iterable, Iterator

from agentspeak.program import Rule
from agentspeak.terms import DEFAULT_NS_NAME, Literal, Term, Var, resolve, split_ns

_SOURCE = "source"


def _first_arg_key(lit: Literal):
    if not lit.args:
        return None
    a = lit.args[0]
    t = type(a)
    if t is int or t is float or t is str:
        return a
    if t is Literal and not a.args:
        return ("atom", a.functor, a.neg)
    return None  # structures, lists: no first-argument index (still found by full scan)


class _Entry:
    __slots__ = ("seq", "lit")

    def __init__(self, seq: int, lit: Literal) -> None:
        self.seq, self.lit = seq, lit


class _Bucket:
    """Beliefs of one key, ordered by ``seq``; sorted views are cached until the next change."""

    __slots__ = ("entries", "by_arg", "_sorted", "_sorted_by_arg")

    def __init__(self) -> None:
        # the arguments of a belief (its literal without annotations: the bucket fixes the rest) -> entry
        self.entries: dict[tuple, _Entry] = {}
        self.by_arg: dict[object, dict[tuple, _Entry]] = {}
        self._sorted: list[Literal] | None = None
        self._sorted_by_arg: dict[object, list[Literal]] = {}

    def changed(self) -> None:
        self._sorted = None
        self._sorted_by_arg.clear()

    def all(self) -> list[Literal]:
        s = self._sorted
        if s is None:
            s = self._sorted = [e.lit for e in sorted(self.entries.values(), key=lambda e: e.seq)]
        return s

    def with_first_arg(self, key) -> list[Literal]:
        s = self._sorted_by_arg.get(key)
        if s is None:
            d = self.by_arg.get(key)
            s = [e.lit for e in sorted(d.values(), key=lambda e: e.seq)] if d else []
            self._sorted_by_arg[key] = s
        return s


_SELECT_OPTION_KEY = (False, "select__option", 4)


class BeliefBase:
    """Facts and rules of one agent."""

    def __init__(self) -> None:
        self._facts: dict[tuple, _Bucket] = {}
        self._rules: dict[tuple, list[Rule]] = {}
        self._front = itertools.count(-1, -1)
        self._back = itertools.count(1)
        self.size = 0
        self.select_option = False  # a select__option/4 rule chooses among a goal's options (Jason 3.3)

    # -- facts -------------------------------------------------------------------------------
    def add(self, lit: Literal, at_end: bool = False) -> Literal | None:
        """Add (or merge annotations of) a ground literal. Returns the literal as it should be
        reported in the ``+b`` event (only the new annotations), or None if nothing changed."""
        args = lit.args
        key = (lit.neg, lit.functor, len(args))  # lit.key, without the property's call
        bucket = self._facts.get(key)
        if bucket is None:
            bucket = self._facts[key] = _Bucket()
        entry = bucket.entries.get(args)
        if entry is None:
            entry = _Entry(next(self._back) if at_end else next(self._front), lit)
            bucket.entries[args] = entry
            ak = _first_arg_key(lit)
            if ak is not None:
                by_arg = bucket.by_arg.get(ak)
                if by_arg is None:
                    by_arg = bucket.by_arg[ak] = {}
                by_arg[args] = entry
            bucket._sorted = None  # bucket.changed(), inlined
            if bucket._sorted_by_arg:
                bucket._sorted_by_arg.clear()
            self.size += 1
            return lit
        old = entry.lit
        new_annots = [a for a in lit.annots or () if not old.annots or a not in old.annots]
        if not new_annots:
            return None
        entry.lit = Literal(old.functor, old.args, (old.annots or ()) + tuple(new_annots), old.neg)
        bucket.changed()
        return Literal(old.functor, old.args, tuple(new_annots), old.neg)

    def remove(self, lit: Literal, all_annots: bool = False) -> Literal | None:
        """Remove ``lit``'s annotations from the stored belief (all of it if ``lit`` has none).
        Returns the literal for the ``-b`` event (the removed annotations), or None. With
        ``all_annots``, nothing is removed unless the belief has every annotation of ``lit``."""
        bucket = self._facts.get((lit.neg, lit.functor, len(lit.args)))
        if bucket is None:
            return None
        plain = lit.args
        entry = bucket.entries.get(plain)
        if entry is None:
            return None
        old = entry.lit
        if not lit.annots:
            removed = old
            remaining: tuple = ()
        else:
            old_annots = old.annots or ()
            gone = tuple([a for a in lit.annots if a in old_annots])
            if not gone or (all_annots and len(gone) != len(lit.annots)):
                return None
            remaining = tuple(a for a in old.annots or () if a not in gone)
            removed = Literal(old.functor, old.args, gone, old.neg)
        if not any(isinstance(a, Literal) and a.functor == _SOURCE for a in remaining):
            del bucket.entries[plain]
            ak = _first_arg_key(old)
            if ak is not None:
                d = bucket.by_arg.get(ak)
                if d is not None:
                    d.pop(plain, None)
                    if not d:   # its key goes too: percepts whose first argument keeps changing (a time, a
                        del bucket.by_arg[ak]   # position) would otherwise leave one empty index per value
            self.size -= 1
        else:
            entry.lit = Literal(old.functor, old.args, remaining, old.neg)
        bucket.changed()
        return removed

    def get(self, lit: Literal) -> Literal | None:
        """The stored belief equal to ``lit`` without annotations."""
        bucket = self._facts.get(lit.key)
        if bucket is None:
            return None
        e = bucket.entries.get(lit.args)
        return e.lit if e else None

    def candidates(self, lit: Literal, b: dict) -> list[Literal]:
        """Stored beliefs that may unify with ``lit`` (first-argument index when it is bound)."""
        return self.candidates_by_key((lit.neg, lit.functor, len(lit.args)), lit, b)

    def candidates_by_key(self, key: tuple, lit: Literal, b: dict) -> list[Literal]:
        """``candidates`` when the caller already knows ``lit.key`` (compiled formulas do)."""
        bucket = self._facts.get(key)
        if bucket is None:
            return []
        if lit.args:
            a = lit.args[0]
            while type(a) is Var:
                v = b.get(a)
                if v is None:
                    break
                a = v
            t = type(a)
            if t is int or t is float or t is str:
                return bucket.with_first_arg(a)
            if t is Literal and not a.args:
                return bucket.with_first_arg(("atom", a.functor, a.neg))
        s = bucket._sorted
        return s if s is not None else bucket.all()

    def in_every_ns(self, body: Term) -> tuple[list[Literal], list[Rule]]:
        """The beliefs and rules of every name space that ``NS::body`` may match (``body`` a literal without
        a name space, or a variable: then every belief)."""
        if type(body) is not Literal:
            return list(self.literals()), []
        want = (body.neg, body.functor, len(body.args))
        facts = [lit for key, bucket in self._facts.items() if _same_but_ns(key, want) for lit in bucket.all()]
        rules = [r for key, rs in self._rules.items() if _same_but_ns(key, want) for r in rs]
        return facts, rules

    def in_namespace(self, ns: str) -> list[Literal]:
        """The beliefs of one name space (what a free variable as a query ranges over)."""
        return [lit for key, bucket in self._facts.items() if split_ns(key[1])[0] == ns for lit in bucket.all()]

    def namespaces(self) -> list[str]:
        """The name spaces of the beliefs and rules, ``default`` first (Jason's ``getNameSpaces``)."""
        seen = {DEFAULT_NS_NAME: None}
        for key in itertools.chain(self._facts, self._rules):
            seen.setdefault(split_ns(key[1])[0], None)
        return list(seen)

    def literals(self) -> Iterator[Literal]:
        for bucket in self._facts.values():
            yield from bucket.all()

    def of_key(self, key: tuple) -> list[Literal]:
        bucket = self._facts.get(key)
        return bucket.all() if bucket else []

    def args_of_key(self, key: tuple):
        """The arguments (a tuple each) of the beliefs of ``key`` (negated?, functor, arity), in no particular
        order: a view of the index, without sorting the beliefs as ``of_key`` does."""
        bucket = self._facts.get(key)
        return bucket.entries.keys() if bucket else ()

    def clear_percepts(self) -> None:
        for lit in list(self.literals()):
            if any(isinstance(a, Literal) and a.functor == _SOURCE and a.args and a.args[0] == PERCEPT for a in lit.annots or ()):
                self.remove(Literal(lit.functor, lit.args, (Literal(_SOURCE, (PERCEPT,)),), lit.neg))

    # -- rules -------------------------------------------------------------------------------
    def add_rule(self, rule: Rule, at_end: bool = True) -> None:
        rules = self._rules.setdefault(rule.head.key, [])
        if rule.head.key == _SELECT_OPTION_KEY:
            self.select_option = True
        if at_end:
            rules.append(rule)
        else:
            rules.insert(0, rule)

    def remove_rule(self, rule: Rule) -> bool:
        rules = self._rules.get(rule.head.key, [])
        for i, r in enumerate(rules):
            if str(r) == str(rule):
                del rules[i]
                if rule.head.key == _SELECT_OPTION_KEY and not rules:
                    self.select_option = False
                return True
        return False

    def rules_for(self, lit: Literal) -> list[Rule]:
        return self._rules.get((lit.neg, lit.functor, len(lit.args)), ())

    def has_rules(self, key: tuple) -> bool:
        return bool(self._rules.get(key))

    def rules(self) -> Iterable[Rule]:
        for rules in self._rules.values():
            yield from rules

    def __len__(self) -> int:
        return self.size


def _same_but_ns(key: tuple, want: tuple) -> bool:
    return key[0] == want[0] and key[2] == want[2] and split_ns(key[1])[1] == want[1]


SELF = Literal("self")
PERCEPT = Literal("percept")


def source(who: Term) -> Literal:
    return Literal(_SOURCE, (who,))


SOURCE_SELF = source(SELF)
SOURCE_PERCEPT = source(PERCEPT)


def has_source(lit: Literal) -> bool:
    return any(isinstance(a, Literal) and a.functor == _SOURCE and len(a.args) == 1 for a in lit.annots or ())


def with_source(lit: Literal, who: Term) -> Literal:
    return lit.add_annot(source(who))


__all__ = ["BeliefBase", "SELF", "PERCEPT", "SOURCE_SELF", "SOURCE_PERCEPT", "source", "has_source",
           "with_source", "resolve"]
