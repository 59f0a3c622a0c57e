"""AgentSpeak terms: the bottom layer, with no knowledge of agents.

Representation (chosen for speed in CPython, see benchmarks/bench_asl.py):

* numbers are Python ``int`` / ``float`` (Jason's are doubles; ``format_number`` prints like Jason);
* strings are Python ``str``; atoms and structures are ``Literal`` (an atom is a Literal without
  arguments); lists are ``Cons`` cells ending in ``NIL`` so ``[H|T]`` unifies structurally;
* variables are ``Var`` objects compared by identity; a variable's value lives in a *bindings*
  dict owned by whoever is solving (an intended means, a query), never in the variable itself,
  so a plan is shared by all its running instances without copying;
* ``Arith``, ``Rel``, ``And``, ``Or``, ``Not`` are expression nodes, evaluated on demand.

Algorithms that walk lists loop along the tail instead of recursing, so 100,000-element lists
do not hit Python's recursion limit.
"""
from __future__ import annotations

import itertools
import math
import operator
from typing import Any, Iterator

Term = Any
"""A term: int | float | str | Literal | Cons | Var | expression node | plan term."""

Bindings = dict
"""A substitution: Var -> Term. Owned by one intended means or one query."""

_fresh_ids = itertools.count(1)


class Var:
    """A logic variable. Identity is the variable; ``name`` is only for printing."""

    __slots__ = ("name",)
    annots = None   # a free variable as a query matches beliefs whole (agentspeak.solver reads a goal's annots)

    def __init__(self, name: str = "_") -> None:
        self.name = name

    def __repr__(self) -> str:
        return self.name

    @staticmethod
    def fresh(hint: str = "_") -> "Var":
        """A brand-new variable nobody else holds (used when renaming)."""
        return Var(f"_{next(_fresh_ids)}{hint if hint != '_' else ''}")


class AnnotatedVar(Var):
    """A variable with annotations, ``X[a]`` or ``F[error(E)|T]``. As in Jason, it unifies with a literal
    whose annotations include its own (binding the tail to the rest), and the variable is bound to that
    literal without annotations (``agentspeak.unify``)."""

    __slots__ = ("var", "annots", "annot_tail")

    def __init__(self, var: Var, annots: tuple, tail: Var | None) -> None:
        super().__init__(var.name)
        self.var, self.annots, self.annot_tail = var, tuple(annots or ()), tail

    def as_pattern(self, functor: str, args: tuple, neg: bool) -> "Literal":
        """The literal ``functor(args)[annots|tail]`` (to match annotations with ``unify_annots``)."""
        return Literal(functor, args, self.annots or None, neg, self.annot_tail)

    def resolve(self, b, depth: int = 0):
        value = resolve(self.var, b, depth)
        if type(value) is Literal:
            annots = tuple(resolve(a, b, depth + 1) for a in self.annots)
            tail = resolve(self.annot_tail, b, depth + 1) if self.annot_tail is not None else None
            if type(tail) is Var:
                return Literal(value.functor, value.args, (value.annots or ()) + annots, value.neg, tail)
            if tail is not None:
                annots += tuple(list_items_or_empty(tail))
            return Literal(value.functor, value.args, (value.annots or ()) + annots or None, value.neg,
                           value.annot_tail)
        if type(value) is Var:
            return AnnotatedVar(value, tuple(resolve(a, b) for a in self.annots),
                                resolve(self.annot_tail, b) if self.annot_tail is not None else None)
        return value

    def without_annots(self) -> Var:
        return self.var

    def rename(self, mapping: dict) -> "AnnotatedVar":
        return AnnotatedVar(rename(self.var, mapping), tuple(rename(a, mapping) for a in self.annots),
                            rename(self.annot_tail, mapping) if self.annot_tail is not None else None)

    def subterms(self) -> list:
        return [self.var, *self.annots] + ([self.annot_tail] if self.annot_tail is not None else [])

    def __eq__(self, other: object) -> bool:
        return (type(other) is AnnotatedVar and other.var is self.var and other.annots == self.annots
                and other.annot_tail is self.annot_tail)

    def __hash__(self) -> int:
        return hash((id(self.var), self.annots))

    def __repr__(self) -> str:
        inner = ",".join(to_str(a) for a in self.annots)
        if self.annot_tail is not None:
            inner += "|" + to_str(self.annot_tail)
        return f"{self.var.name}[{inner}]"


class Literal:
    """An atom, a structure or a predicate: ``~functor(args)[annots]``.

    ``annots`` is a tuple kept sorted and without duplicates when ground (Jason keeps annotations
    as a sorted set), or ``None`` for no annotations. ``annot_tail`` is the ``|T`` of ``[a|T]``.
    The message path also builds literals without ``__init__`` (see ``agentspeak.agent._new``).
    """

    __slots__ = ("functor", "args", "annots", "neg", "annot_tail", "_hash")

    def __init__(self, functor: str, args: tuple = (), annots: tuple | None = None,
                 neg: bool = False, annot_tail: Var | None = None) -> None:
        self.functor = functor
        self.args = args
        if annots:
            # one annotation (the usual source(...)) is already normal
            self.annots = annots if len(annots) == 1 and type(annots) is tuple else normalise_annots(annots)
        else:
            self.annots = None
        self.neg = neg
        self.annot_tail = annot_tail
        self._hash = None

    # -- identity --------------------------------------------------------------------------
    @property
    def key(self) -> tuple:
        """The belief-base and plan-library index: (negated?, functor, arity)."""
        return (self.neg, self.functor, len(self.args))

    def __eq__(self, other: object) -> bool:
        if self is other:
            return True
        if not isinstance(other, Literal):
            return False
        return (self.functor == other.functor and self.neg == other.neg
                and self.args == other.args and self.annots == other.annots
                and self.annot_tail is other.annot_tail)

    def __hash__(self) -> int:
        h = self._hash
        if h is None:
            h = self._hash = hash((self.functor, self.neg, self.args, self.annots))
        return h

    def __reduce__(self) -> tuple:
        # Pickled without ``_hash``: string hashes differ between processes (PYTHONHASHSEED), so a
        # cached hash written by one process is wrong in the next (agentspeak/parse_cache.py).
        return (_literal, (self.functor, self.args, self.annots, self.neg, self.annot_tail))

    def __lt__(self, other: object) -> bool:
        return compare(self, other) < 0

    def is_atom(self) -> bool:
        return not self.args and not self.annots and not self.neg

    def with_annots(self, annots: tuple | None, annot_tail: Var | None = None) -> "Literal":
        return Literal(self.functor, self.args, annots, self.neg, annot_tail)

    def without_annots(self) -> "Literal":
        if not self.annots and self.annot_tail is None:
            return self
        return Literal(self.functor, self.args, None, self.neg)

    def add_annot(self, annot: Term) -> "Literal":
        if self.annots and annot in self.annots:
            return self
        return Literal(self.functor, self.args, (self.annots or ()) + (annot,), self.neg, self.annot_tail)

    def sources(self) -> list:
        return [a.args[0] for a in self.annots or () if isinstance(a, Literal) and a.functor == "source" and len(a.args) == 1]

    def __repr__(self) -> str:
        return to_str(self)

    __str__ = __repr__


def atom(name: str) -> Literal:
    """The atom ``name`` (a Literal without arguments)."""
    return Literal(name)


def normalise_annots(annots: tuple) -> tuple:
    """Sorted, duplicate-free tuple when every element is ground; source order otherwise."""
    if len(annots) == 1:
        return tuple(annots)
    if all(is_ground(a) for a in annots):
        unique: list = []
        for a in annots:
            if a not in unique:
                unique.append(a)
        unique.sort(key=SortKey)
        return tuple(unique)
    return tuple(annots)


class Cons:
    """A list cell ``[head|tail]``; ``NIL`` is the empty list."""

    __slots__ = ("head", "tail")

    def __init__(self, head: Term, tail: Term) -> None:
        self.head = head
        self.tail = tail

    def __eq__(self, other: object) -> bool:
        a, b = self, other
        while isinstance(a, Cons) and isinstance(b, Cons):
            if a is b:
                return True
            if not (a.head == b.head):
                return False
            a, b = a.tail, b.tail
        if isinstance(a, Cons) or isinstance(b, Cons):
            return False
        return a == b

    def __hash__(self) -> int:
        h = 17
        t: Term = self
        while isinstance(t, Cons):
            h = hash((h, t.head))
            t = t.tail
        return hash((h, t if not isinstance(t, Var) else id(t)))

    def __iter__(self) -> Iterator[Term]:
        t: Term = self
        while isinstance(t, Cons):
            yield t.head
            t = t.tail

    def __repr__(self) -> str:
        return to_str(self)


class _Nil:
    """The empty list ``[]`` (a singleton)."""

    __slots__ = ()

    def __iter__(self) -> Iterator[Term]:
        return iter(())

    def __repr__(self) -> str:
        return "[]"

    def __eq__(self, other: object) -> bool:
        return other is self

    def __hash__(self) -> int:
        return 0x5EED

    def __reduce__(self) -> str:
        return "NIL"      # unpickled as this module's NIL: code tests ``t is NIL``


NIL = _Nil()


def _literal(functor: str, args: tuple, annots: tuple | None, neg: bool, annot_tail: Var | None) -> Literal:
    """A literal from its pickled fields (already normal: ``__init__``'s annotation sort is skipped)."""
    lit = Literal.__new__(Literal)
    lit.functor, lit.args, lit.annots, lit.neg, lit.annot_tail, lit._hash = functor, args, annots, neg, annot_tail, None
    return lit


def make_list(items, tail: Term = None) -> Term:
    """Build a Cons list from a Python iterable (``tail`` defaults to ``NIL``)."""
    result = NIL if tail is None else tail
    for item in reversed(list(items)):
        result = Cons(item, result)
    return result


def is_list(t: Term) -> bool:
    return t is NIL or isinstance(t, Cons)


def list_items(t: Term) -> list:
    """The elements of a proper list (raises ``TypeError`` for a partial list)."""
    out = []
    while isinstance(t, Cons):
        out.append(t.head)
        t = t.tail
    if t is not NIL:
        items = getattr(t, "list_items", None) if not out else None
        if items is not None:  # a set or a queue (agentspeak.stdlib.containers) is seen as its elements
            return items()
        raise TypeError(f"not a proper list (tail is {to_str(t)})")
    return out


# -- expressions ----------------------------------------------------------------------------
class Arith:
    """An arithmetic expression ``left op right`` (``right`` is None for unary minus)."""

    __slots__ = ("op", "left", "right")

    def __init__(self, op: str, left: Term, right: Term = None) -> None:
        self.op, self.left, self.right = op, left, right

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Arith) and self.op == other.op and self.left == other.left
                and self.right == other.right)

    def __hash__(self) -> int:
        return hash((self.op, self.left, self.right))

    def __repr__(self) -> str:
        return to_str(self)


class Rel:
    """A relational expression: ``< <= > >= == \\== = =..``."""

    __slots__ = ("op", "left", "right")

    def __init__(self, op: str, left: Term, right: Term) -> None:
        self.op, self.left, self.right = op, left, right

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Rel) and self.op == other.op and self.left == other.left
                and self.right == other.right)

    def __hash__(self) -> int:
        return hash(("rel", self.op, self.left, self.right))

    def __repr__(self) -> str:
        return to_str(self)


class And:
    __slots__ = ("left", "right")

    def __init__(self, left: Term, right: Term) -> None:
        self.left, self.right = left, right

    def __eq__(self, other: object) -> bool:
        return isinstance(other, And) and self.left == other.left and self.right == other.right

    def __hash__(self) -> int:
        return hash(("&", self.left, self.right))

    def __repr__(self) -> str:
        return to_str(self)


class Or:
    __slots__ = ("left", "right")

    def __init__(self, left: Term, right: Term) -> None:
        self.left, self.right = left, right

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Or) and self.left == other.left and self.right == other.right

    def __hash__(self) -> int:
        return hash(("|", self.left, self.right))

    def __repr__(self) -> str:
        return to_str(self)


class Not:
    __slots__ = ("arg",)

    def __init__(self, arg: Term) -> None:
        self.arg = arg

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Not) and self.arg == other.arg

    def __hash__(self) -> int:
        return hash(("not", self.arg))

    def __repr__(self) -> str:
        return to_str(self)


class Func:
    """An arithmetic function call ``math.max(X, 3)`` (Jason's ArithFunctionTerm).

    The parser makes one when a literal's name and arity are a registered function; ``spec`` is
    that function (``agentspeak.stdlib.registry.FunctionSpec``: ``evaluate(args)`` and
    ``unground_ok``). Resolving evaluates it once its arguments are ground, like ``Arith``.
    """

    __slots__ = ("name", "args", "spec")

    def __init__(self, name: str, args: tuple, spec: Any) -> None:
        self.name, self.args, self.spec = name, args, spec

    def resolve(self, b: Bindings, depth: int = 0) -> Term:
        args = tuple([resolve(a, b, depth + 1) for a in self.args])
        if all(is_ground(a) for a in args):
            value = self.spec.evaluate(args)
            if value is not None:  # None: not now (it needs an agent and none is running)
                return value
        elif self.spec.unground_ok:
            # tried now, and left for later if it cannot be computed yet (Jason's capply: a function of
            # unbound arguments stays as it is, e.g. a rule function in a .findall query not yet run)
            try:
                value = self.spec.evaluate(args)
            except Exception:  # noqa: BLE001 - any failure here only means "not yet"
                value = None
            if value is not None:
                return value
        return Func(self.name, args, self.spec)

    def rename(self, mapping: dict) -> "Func":
        return Func(self.name, tuple([rename(a, mapping) for a in self.args]), self.spec)

    def subterms(self) -> list:
        return list(self.args)

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Func) and self.name == other.name and self.args == other.args)

    def __hash__(self) -> int:
        return hash(("func", self.name, self.args))

    def __repr__(self) -> str:
        return to_str(self)

    __str__ = __repr__


# -- name spaces (Jason's modules) ------------------------------------------------------------
DEFAULT_NS_NAME = "default"
NS_SEP = "::"
LOCAL_NS_PREFIX = "#"
"""A local name space is named ``#<n><name>`` (Jason's ``NameSpace.LOCAL_PREFIX``): unique per inclusion."""


def split_ns(functor: str) -> tuple[str, str]:
    """``"tv::cfp"`` -> ``("tv", "cfp")``; a functor without a name space is in ``default``.

    A literal of a constant name space keeps it in its functor's text (``tv::cfp``): the belief base and
    plan library index it apart and unification compares it with the functor, at no cost; only a name
    space that is a variable needs a term of its own (``NsTerm``)."""
    if NS_SEP in functor and functor[0] != "'":
        ns, _, name = functor.partition(NS_SEP)
        return ns, name
    return DEFAULT_NS_NAME, functor


def in_ns(ns: str, name: str) -> str:
    """The functor of ``name`` in name space ``ns`` (``default`` adds nothing)."""
    return name if ns == DEFAULT_NS_NAME else ns + NS_SEP + name


_NS_ATOMS: dict = {}


def ns_atom(name: str) -> "Literal":
    """The atom named ``name``, one object per name, the table bounded under hostile input: name spaces,
    and the senders of messages (``agentspeak.communication``)."""
    found = _NS_ATOMS.get(name)
    if found is None:
        found = Literal(name)
        if len(_NS_ATOMS) < 10_000:
            _NS_ATOMS[name] = found
    return found


class NsTerm:
    """``NS::lit`` where the name space ``NS`` is a variable (or ``ns::X``, a variable in a name space).

    ``body`` is the literal (its functor without a name space), a ``Var`` or an ``AnnotatedVar``.
    Resolved with ``NS`` bound to an atom it is the plain ``Literal`` of that name space. It unifies with
    a literal of any name space, binding ``NS`` to that name space (``default`` for a literal without
    one) and the body to the literal without its name space (a variable's value carries no name space,
    as in Jason). A variable never takes a local name space (``#1priv``): it stays private to its module.
    Unification: ``agentspeak.unify.unify_ns``."""

    __slots__ = ("ns", "body")
    annots = None   # the solver asks a query for its annotations (NsTerm goals match them by unification)

    def __init__(self, ns: Term, body: Term) -> None:
        self.ns, self.body = ns, body

    def resolve(self, b: Bindings, depth: int = 0) -> Term:
        ns = resolve(self.ns, b, depth + 1)
        body = resolve(self.body, b, depth + 1)
        if type(ns) is Literal and not ns.args:
            if type(body) is Literal:
                name = split_ns(body.functor)[1]
                if "." in name and name[0] != "'":
                    return body   # an internal action has no name space (a variable bound to `.print(x)`)
                return Literal(in_ns(ns.functor, name), body.args, body.annots, body.neg, body.annot_tail)
            if type(body) is not Var and type(body) is not AnnotatedVar:
                return body   # a number, a string, a list: no name space to give
        return NsTerm(ns, body)

    def rename(self, mapping: dict) -> "NsTerm":
        return NsTerm(rename(self.ns, mapping), rename(self.body, mapping))

    def subterms(self) -> list:
        return [self.ns, self.body]

    def __eq__(self, other: object) -> bool:
        return type(other) is NsTerm and other.ns == self.ns and other.body == self.body

    def __hash__(self) -> int:
        return hash(("ns", self.ns, self.body))

    def __repr__(self) -> str:
        return to_str(self)

    __str__ = __repr__


EXPRESSION_TYPES = (Arith, Rel, And, Or, Not, Func, NsTerm)


# -- binding access -------------------------------------------------------------------------
#: The deepest term an agent may build at run time (``resolve``): rules, loops and goals can nest a term
#: level after level (``!g(N-1, f(T))``) past what any parsed clause may (``nesting.MAX_NESTING``). Walked
#: by the compiled interpreter, a term 19,000 deep overflowed the C stack (SIGSEGV, the agent gone without
#: a log line); from source Python's recursion limit stops it near 950 levels. 1,000 levels keep both
#: builds alike and leave the walkers (printing, hashing, comparing) well inside a 2 MiB thread stack.
MAX_TERM_DEPTH = 1000


def deref(t: Term, b: Bindings) -> Term:
    """Follow variable bindings until a non-variable or an unbound variable."""
    while type(t) is Var:
        v = b.get(t, t)
        if v is t:
            return t
        t = v
    return t


def resolve(t: Term, b: Bindings, depth: int = 0) -> Term:
    """Apply bindings everywhere in ``t`` and evaluate ground arithmetic (Jason's ``capply``).

    ``depth``: how deep ``t`` sits in the term being resolved. Past ``MAX_TERM_DEPTH`` it raises
    ``RecursionError`` (the intention fails: "a term too deep or cyclic to work with"), compiled or not.
    Every term an agent builds at run time goes through here, so none gets deeper than that."""
    if depth > MAX_TERM_DEPTH:
        raise RecursionError(f"a term nested deeper than {MAX_TERM_DEPTH} levels")
    tt = type(t)
    if tt is Var:
        while True:  # follow a chain of variables in a loop (rules can build chains 100,000 long)
            v = b.get(t)
            if v is None:
                return t
            if type(v) is not Var:
                return resolve(v, b, depth)
            t = v
    if tt is Literal:
        if not t.args and t.annots is None and t.annot_tail is None:
            return t
        if t.args:
            out = []
            for a in t.args:  # the common argument shapes without a call
                ta = type(a)
                if ta is int or ta is float or ta is str:
                    out.append(a)
                    continue
                if ta is Var:
                    v = b.get(a)
                    if v is None:
                        out.append(a)
                        continue
                    tv = type(v)
                    if tv is int or tv is float or tv is str:
                        out.append(v)
                        continue
                    a = v
                out.append(resolve(a, b, depth + 1))
            args = tuple(out)
        else:
            args = ()
        annots = t.annots
        tail = t.annot_tail
        if annots is not None or tail is not None:
            items = [resolve(a, b, depth + 1) for a in annots] if annots else []
            if tail is not None:
                tv = resolve(tail, b, depth + 1)
                if type(tv) is Var:
                    tail = tv
                else:
                    tail = None
                    items.extend(list_items_or_empty(tv))
            annots = tuple(items) if items else None
        return Literal(t.functor, args, annots, t.neg, tail)
    if tt is int or tt is float or tt is str:
        return t
    if tt is Cons:
        heads = []
        cur: Term = t
        while True:
            if type(cur) is Var:
                nxt = b.get(cur)
                if nxt is None:
                    break
                cur = nxt
                continue
            if type(cur) is not Cons:
                break
            heads.append(resolve(cur.head, b, depth + 1))
            cur = cur.tail
        tail_value = resolve(cur, b, depth) if cur is not NIL else NIL
        for h in reversed(heads):
            tail_value = Cons(h, tail_value)
        return tail_value
    if tt is Arith:
        left = t.left
        if type(left) is Var:
            left = b.get(left, left)
        if type(left) is not int and type(left) is not float:
            left = resolve(left, b, depth + 1)
        right = t.right
        if right is not None:
            if type(right) is Var:
                right = b.get(right, right)
            if type(right) is not int and type(right) is not float:
                right = resolve(right, b, depth + 1)
            if type(left) is int and type(right) is int:  # the common case, without eval_arith
                int_op = INT_OPS.get(t.op)
                if int_op is not None:
                    r = int_op(left, right)
                    return r if -_EXACT < r < _EXACT else float(r)  # normalise_number, inlined
        value = try_eval_arith(t.op, left, right)
        if value is not None:
            return value
        check_operands(t.op, left, right)
        return Arith(t.op, left, right)
    if tt is Rel:
        return Rel(t.op, resolve(t.left, b, depth + 1), resolve(t.right, b, depth + 1))
    if tt is And:
        return And(resolve(t.left, b, depth + 1), resolve(t.right, b, depth + 1))
    if tt is Or:
        return Or(resolve(t.left, b, depth + 1), resolve(t.right, b, depth + 1))
    if tt is Not:
        return Not(resolve(t.arg, b, depth + 1))
    resolver = getattr(t, "resolve", None)
    if resolver is not None:   # a term that resolves itself, ``resolve(b, depth)``: the count goes on inside it
        return resolver(b, depth)
    return t


def list_items_or_empty(t: Term) -> list:
    try:
        return list_items(t)
    except TypeError:
        return [t]


def variables(t: Term, out: list | None = None) -> list:
    """The distinct variables of ``t`` in first-occurrence order."""
    if out is None:
        out = []
    stack = [t]
    while stack:
        x = stack.pop()
        tx = type(x)
        if tx is Var:
            if x not in out:
                out.append(x)
        elif tx is Literal:
            if x.annot_tail is not None:
                stack.append(x.annot_tail)
            if x.annots:
                stack.extend(reversed(x.annots))
            stack.extend(reversed(x.args))
        elif tx is Cons:
            stack.append(x.tail)
            stack.append(x.head)
        elif tx is Arith:
            if x.right is not None:
                stack.append(x.right)
            stack.append(x.left)
        elif tx in (Rel, And, Or):
            stack.append(x.right)
            stack.append(x.left)
        elif tx is Not:
            stack.append(x.arg)
        else:
            sub = getattr(x, "subterms", None)
            if sub is not None:
                stack.extend(reversed(sub()))
    return out


def term_height(t: Term, limit: int = MAX_TERM_DEPTH) -> int:
    """How many levels ``t`` nests, counted as ``resolve`` counts them (a list's elements one level down, its
    tail on the same), with a stack rather than the C stack; the walk stops past ``limit`` (returns
    ``limit + 1``): what matters is whether a term is too deep, not by how much."""
    best = 0
    stack = [(t, 0)]
    while stack:
        x, level = stack.pop()
        if level > best:
            best = level
            if best > limit:
                return best
        tx = type(x)
        d = level + 1
        if tx is Literal:
            stack.extend([(a, d) for a in x.args])
            if x.annots:
                stack.extend([(a, d) for a in x.annots])
        elif tx is Cons:
            stack.append((x.head, d))
            stack.append((x.tail, level))
        elif tx is Arith:
            stack.append((x.left, d))
            if x.right is not None:
                stack.append((x.right, d))
        elif tx is Rel or tx is And or tx is Or:
            stack.append((x.left, d))
            stack.append((x.right, d))
        elif tx is Not:
            stack.append((x.arg, d))
        elif tx is not Var and tx is not int and tx is not float and tx is not str:
            sub = getattr(x, "subterms", None)
            if sub is not None:
                stack.extend([(a, d) for a in sub()])
    return best


def is_ground(t: Term, depth: int = 0) -> bool:
    """No variable anywhere in ``t`` (stops at the first; the common shapes without a list walk;
    deep nesting goes to the loop of ``variables``, which needs no Python stack)."""
    tt = type(t)
    if depth > 50:
        return not variables(t)
    if tt is int or tt is float or tt is str:
        return True
    if tt is Literal:
        if t.annot_tail is not None:
            return False
        for a in t.args:
            ta = type(a)
            if ta is int or ta is float or ta is str:
                continue
            if ta is Var or not is_ground(a, depth + 1):
                return False
        if t.annots is not None:
            for a in t.annots:
                if type(a) is Var or not is_ground(a, depth + 1):
                    return False
        return True
    if tt is Var:
        return False
    return not variables(t)


def rename(t: Term, mapping: dict) -> Term:
    """Copy ``t`` replacing each variable by a fresh one (consistently, through ``mapping``)."""
    tt = type(t)
    if tt is Var:
        v = mapping.get(t)
        if v is None:
            v = mapping[t] = Var(t.name)
        return v
    if tt is Literal:
        if not t.args and t.annots is None and t.annot_tail is None:
            return t
        lit = Literal.__new__(Literal)
        lit.functor = t.functor
        lit.args = tuple([rename(a, mapping) for a in t.args]) if t.args else ()
        lit.annots = tuple([rename(a, mapping) for a in t.annots]) if t.annots else None
        lit.neg = t.neg
        lit.annot_tail = rename(t.annot_tail, mapping) if t.annot_tail is not None else None
        lit._hash = None
        return lit
    if tt is int or tt is float or tt is str:
        return t
    if tt is Cons:
        heads = []
        cur = t
        while type(cur) is Cons:
            heads.append(rename(cur.head, mapping))
            cur = cur.tail
        result = rename(cur, mapping)
        for h in reversed(heads):
            result = Cons(h, result)
        return result
    if tt is Arith:
        return Arith(t.op, rename(t.left, mapping), rename(t.right, mapping) if t.right is not None else None)
    if tt is Rel:
        return Rel(t.op, rename(t.left, mapping), rename(t.right, mapping))
    if tt is And:
        return And(rename(t.left, mapping), rename(t.right, mapping))
    if tt is Or:
        return Or(rename(t.left, mapping), rename(t.right, mapping))
    if tt is Not:
        return Not(rename(t.arg, mapping))
    renamer = getattr(t, "rename", None)
    if renamer is not None:
        return renamer(mapping)
    return t


# -- arithmetic (Java semantics) ------------------------------------------------------------
class ArithmeticError_(TypeError):
    """A non-numeric operand or a division by zero in an arithmetic expression."""


def _num(x: Term, op: str) -> float | int:
    if type(x) is int or type(x) is float:
        return x
    if isinstance(x, bool):
        return int(x)
    raise ArithmeticError_(f"'{op}' needs numbers, got {to_str(x)}")


_EXACT = 2 ** 53
INT_OPS = {"+": operator.add, "-": operator.sub, "*": operator.mul}
"""Operators whose integer result needs no more than Python's own operation (the fast cases of
``resolve`` and of goal posting; division, ``div``, ``mod`` and ``**`` go through ``eval_arith``)."""
"""Integers at least this large are doubles in Jason (they print and compare as such)."""


def normalise_number(x: float | int) -> float | int:
    """Integral floats become ints so that they print and hash like Jason's doubles."""
    if type(x) is float and x.is_integer() and abs(x) < 2 ** 53:
        return int(x)
    if type(x) is int and abs(x) >= 2 ** 53:
        return float(x)
    return x


def _java_int(x: float | int) -> int:
    """Java's ``(int)`` cast: truncation toward zero, saturating at 32 bits... as Jason uses long."""
    return int(x) if not (isinstance(x, float) and (math.isnan(x) or math.isinf(x))) else 0


def eval_arith(op: str, left: Term, right: Term) -> float | int:
    a = _num(left, op)
    if right is None:
        return normalise_number(-a) if op == "-" else a
    c = _num(right, op)
    if op == "+":
        r = a + c
    elif op == "-":
        r = a - c
    elif op == "*":
        r = a * c
    elif op == "/":
        if c == 0:
            r = math.copysign(math.inf, a) if a != 0 else math.nan
        else:
            r = a / c
    elif op == "div":
        ia, ic = _java_int(a), _java_int(c)
        if ic == 0:
            raise ArithmeticError_("division by zero in 'div'")
        q = abs(ia) // abs(ic)
        r = q if (ia >= 0) == (ic >= 0) else -q
    elif op == "mod":  # Java's % on doubles: the sign of the dividend, fractions kept
        if c == 0:
            raise ArithmeticError_("division by zero in 'mod'")
        r = math.fmod(a, c)
        r = int(r) if isinstance(a, int) and isinstance(c, int) else r
    elif op == "**":
        r = float(a) ** c if isinstance(a, float) or isinstance(c, float) or c < 0 else a ** c
    else:
        raise ArithmeticError_(f"unknown arithmetic operator {op!r}")
    return normalise_number(r)


def check_operands(op: str, left: Term, right: Term) -> None:
    """Raise if an operand can never become a number (an atom, a string, a list), so ``X = a + 1``
    fails the formula instead of leaving an expression nobody can evaluate. Operands that may still
    become numbers (unbound variables, expressions over them) keep the expression symbolic."""
    for x in (left, right):
        if isinstance(x, (Literal, str, Cons, _Nil)):
            expr = to_str(Arith(op, left, right))
            raise ArithmeticError_(f"arithmetic on a non-number: {to_str(x)} in {expr}")


def try_eval_arith(op: str, left: Term, right: Term) -> float | int | None:
    """Evaluate when the operands are numbers; None when they are not (yet) numbers."""
    tl = type(left)
    if tl is not int and tl is not float:
        return None
    if right is not None:
        tr = type(right)
        if tr is not int and tr is not float:
            return None
    return eval_arith(op, left, right)


# -- standard order of terms (Jason's Term.compareTo) --------------------------------------
def _type_rank(t: Term) -> int:
    tt = type(t)
    if tt is int or tt is float:
        return 0
    if tt is str or tt is Cons or t is NIL:
        return 1
    if tt is Var:
        return -1
    return 2


def compare(a: Term, b: Term) -> int:
    """Numbers < strings and lists < atoms and structures (by functor, arity, then arguments)."""
    ra, rb = _type_rank(a), _type_rank(b)
    if ra != rb:
        return -1 if ra < rb else 1
    if ra == 0:
        return (a > b) - (a < b)
    if ra == 1:
        la, lb = is_list(a), is_list(b)
        if la and lb:
            ia, ib = iter_list(a), iter_list(b)
            for x, y in zip(ia, ib):
                c = compare(x, y)
                if c:
                    return c
            na, nb = list_len(a), list_len(b)
            return (na > nb) - (na < nb)
        sa, sb = to_str(a), to_str(b)
        return (sa > sb) - (sa < sb)
    if ra == -1:
        return (id(a) > id(b)) - (id(a) < id(b))
    if isinstance(a, Literal) and isinstance(b, Literal):
        if a.neg != b.neg:
            return -1 if not a.neg else 1
        na, nb = len(a.args), len(b.args)
        if na != nb:
            return -1 if na < nb else 1
        if a.functor != b.functor:
            return -1 if a.functor < b.functor else 1
        for x, y in zip(a.args, b.args):
            c = compare(x, y)
            if c:
                return c
        return 0
    sa, sb = to_str(a), to_str(b)
    return (sa > sb) - (sa < sb)


def iter_list(t: Term) -> Iterator[Term]:
    while isinstance(t, Cons):
        yield t.head
        t = t.tail


def list_len(t: Term) -> int:
    n = 0
    while isinstance(t, Cons):
        n += 1
        t = t.tail
    return n


class SortKey:
    """Adapter so ``sorted(terms, key=SortKey)`` uses the standard order of terms."""

    __slots__ = ("t",)

    def __init__(self, t: Term) -> None:
        self.t = t

    def __lt__(self, other: "SortKey") -> bool:
        return compare(self.t, other.t) < 0

    def __eq__(self, other: object) -> bool:
        return isinstance(other, SortKey) and compare(self.t, other.t) == 0


# -- printing (as Jason prints) -------------------------------------------------------------
def format_number(x: float | int) -> str:
    """Jason's NumberTermImpl.toString: integral values without ``.0``; else Java's Double.toString."""
    if type(x) is int:
        if abs(x) < 2 ** 63:
            return str(x)
        try:
            x = float(x)
        except OverflowError:  # beyond a double, as Java's would be (found by the fuzz campaign)
            return "Infinity" if x > 0 else "-Infinity"
    if math.isnan(x):
        return "NaN"
    if math.isinf(x):
        return "Infinity" if x > 0 else "-Infinity"
    if x.is_integer() and abs(x) < 9.2e18:
        return str(int(x))
    return java_double_str(x)


def java_double_str(x: float) -> str:
    """Java's ``Double.toString``: shortest repr, scientific outside [1e-3, 1e7)."""
    r = repr(x)
    ax = abs(x)
    if 1e-3 <= ax < 1e7:
        if "e" in r:  # python chose exponent notation for a value Java prints plainly
            r = format(x, "f").rstrip("0")
            if r.endswith("."):
                r += "0"
        return r
    if ax == 5e-324:  # Double.MIN_VALUE: Java writes two digits where one reads back
        return "4.9E-324" if x > 0 else "-4.9E-324"
    m, exponent = f"{x:.16e}".split("e")
    for prec in range(1, 18):  # the shortest mantissa that reads back as the same double
        cand = f"{x:.{prec - 1}e}"
        if float(cand) == x:
            m, exponent = cand.split("e")
            break
    m = m.rstrip("0") if "." in m else m
    if m.endswith("."):
        m += "0"
    if "." not in m:
        m += ".0"
    return f"{m}E{int(exponent)}"


def _quote_string(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def to_str(t: Term, b: Bindings | None = None) -> str:
    """The Jason text of a term (strings quoted), with bindings applied if given."""
    if b is not None:
        t = resolve(t, b)
    tt = type(t)
    if tt is str:
        return _quote_string(t)
    if tt is int or tt is float:
        return format_number(t)
    if tt is Var:
        return t.name
    if tt is Literal:
        out = "~" + t.functor if t.neg else t.functor
        if t.functor and not _plain_atom(t.functor) and t.functor[0] != "'":
            out = ("~" if t.neg else "") + "'" + t.functor + "'"
        elif t.neg and NS_SEP in t.functor:  # Jason writes the name space first: `ns::~p`
            ns, _, name = t.functor.partition(NS_SEP)
            out = ns + "::~" + name
        if t.args:
            out += "(" + ",".join(to_str(a) for a in t.args) + ")"
        if t.annots or t.annot_tail is not None:
            inner = ",".join(to_str(a) for a in t.annots or ())
            if t.annot_tail is not None:
                inner += ("|" if inner else "") + to_str(t.annot_tail)
            out += "[" + inner + "]"
        return out
    if tt is Cons or t is NIL:
        parts = []
        cur = t
        while type(cur) is Cons:
            parts.append(to_str(cur.head))
            cur = cur.tail
        text = "[" + ",".join(parts)
        if cur is not NIL:
            text += "|" + to_str(cur)
        return text + "]"
    if tt is Arith:
        if t.right is None:
            return f"(-{to_str(t.left)})"
        return f"({to_str(t.left)}{_op_text(t.op)}{to_str(t.right)})"
    if tt is Rel:
        return f"({to_str(t.left)} {t.op} {to_str(t.right)})"
    if tt is And:
        return f"({to_str(t.left)} & {to_str(t.right)})"
    if tt is Or:
        return f"({to_str(t.left)} | {to_str(t.right)})"
    if tt is Not:
        return f"not ({to_str(t.arg)})"
    if tt is Func:
        return t.name + ("(" + ",".join(to_str(a) for a in t.args) + ")" if t.args else "")
    if tt is NsTerm:
        return to_str(t.ns) + NS_SEP + to_str(t.body)
    return str(t)


def _op_text(op: str) -> str:
    return f" {op} " if op in ("div", "mod") else op


def _plain_atom(name: str) -> bool:
    if not name:
        return False
    c = name[0]
    if c == "#" and "::" in name:
        c = "a"
    if not (c.islower() or c == "."):
        return False
    if "::" in name:  # a name space: `family::brother`, a local one `#1priv::state`
        ns, _, rest = name.partition("::")
        if ns.startswith(LOCAL_NS_PREFIX):
            ns = ns.lstrip(LOCAL_NS_PREFIX + "0123456789")
        return _plain_atom(ns) and _plain_atom(rest)
    return all(ch.isalnum() or ch in "_." for ch in name)


def to_print_str(t: Term, b: Bindings | None = None) -> str:
    """What ``.print`` shows: a top-level string without quotes; unbound variables as ``X<no-value>``."""
    if b is not None:
        t = resolve(t, b)
    if type(t) is str:
        return t
    if type(t) is Var:
        return f"{t.name}<no-value>"
    return to_str(t)
