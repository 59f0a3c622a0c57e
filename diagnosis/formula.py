"""Propositional formulas of system descriptions: parse (grammar in ``formula.lark``) and clausify.

The grammar lives in the ``.lark`` file; this module only transforms the parse tree into a small
immutable AST and the AST into CNF. Clausification goes through negation normal form and the
Plaisted-Greenbaum variant of Tseitin's encoding (one implication per auxiliary variable): for every
assignment of the model's own variables the clauses are satisfiable exactly when the formula is true,
which is all that consistency-based diagnosis asks of them.

Lark is imported by the first ``parse_formula``: the AST and the clausifier serve netlists too (``.bench``
models have no formulas), and Lark's import is a large part of a short ``faultmas diagnose`` (issue 23).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Union

if TYPE_CHECKING:
    from lark import Lark, Transformer

from agentspeak.nesting import MAX_NESTING, first_too_deep_bracket, nesting_depth, too_deep_message


@dataclass(frozen=True)
class Const:
    value: bool


@dataclass(frozen=True)
class Atom:
    """A proposition such as ``moved`` or ``hz(scan)``; ``name`` is its canonical text."""
    name: str


@dataclass(frozen=True)
class Ab:
    """The health literal ``AB(component)``: true when the component is abnormal."""
    component: str


@dataclass(frozen=True)
class Not:
    arg: "Formula"


@dataclass(frozen=True)
class And:
    args: tuple["Formula", ...]


@dataclass(frozen=True)
class Or:
    args: tuple["Formula", ...]


Formula = Union[Const, Atom, Ab, Not, And, Or]
Literal = Union[Atom, Ab]


class FormulaSyntaxError(ValueError):
    """A formula that does not parse; ``column`` is 1-based within the formula text."""

    def __init__(self, message: str, column: int | None) -> None:
        super().__init__(message)
        self.column = column


def atom_text(functor: str, args: list[str] | tuple[str, ...]) -> str:
    """Canonical text of an applied atom: ``hz(scan)``, ``timing(a,b)`` (no spaces), as AgentSpeak prints it."""
    return f"{functor}({','.join(args)})"


class _ToAst:
    """The parse tree's rules as AST nodes (made a Lark ``Transformer`` by ``_transformer``)."""

    def plain(self, name):
        text = str(name)
        if text == "true":
            return Const(True)
        if text == "false":
            return Const(False)
        return Atom(text)

    def applied(self, functor, *args):
        names = [str(a) for a in args]
        if str(functor) == "AB":
            if len(names) != 1:
                raise FormulaSyntaxError(f"AB takes one component, got {len(names)}", functor.column)
            return Ab(names[0])
        return Atom(atom_text(str(functor), names))

    def neg(self, _op, arg):
        return Not(arg)

    def conj(self, a, b):
        return And((a, b))

    def disj(self, a, b):
        return Or((a, b))

    def implies(self, a, b):
        return Or((Not(a), b))

    def iff(self, a, b):
        return And((Or((Not(a), b)), Or((a, Not(b)))))


_TOKEN_NAMES = {"LPAR": "'('", "RPAR": "')'", "NAME": "a name", "NOT": "'!'", "COMMA": "','",
                "AMPERSAND": "'&'", "VBAR": "'|'", "__ANON_0": "'<->'", "__ANON_1": "'->'", "$END": "end"}


@lru_cache(maxsize=1)
def _parser() -> Lark:
    from agentspeak.lark_loader import lalr_parser  # first: it refuses lark-parser 0.12 with the fix

    return lalr_parser(Path(__file__).with_name("formula.lark"), maybe_placeholders=False)


@lru_cache(maxsize=1)
def _transformer() -> type[Transformer]:
    from lark import Transformer, v_args

    # the methods copied, not inherited: v_args wraps only methods defined in the class itself
    rules = {name: f for name, f in vars(_ToAst).items() if not name.startswith("__")}
    return v_args(inline=True)(type("_ToAst", (Transformer,), rules))


def parse_formula(text: str) -> Formula:
    """Parse one formula; raises FormulaSyntaxError with the column and what was expected.

    A formula nested deeper than ``MAX_NESTING`` (``!!!...a`` 20,000 times, say) is refused here: the
    transformation, ``literals``, ``_nnf`` and ``to_cnf`` recurse once per level."""
    too_deep = first_too_deep_bracket(text)
    if too_deep is not None:
        raise FormulaSyntaxError(too_deep_message(), too_deep + 1)
    parser = _parser()
    from lark.exceptions import UnexpectedEOF, UnexpectedInput

    try:
        tree = parser.parse(text)
    except UnexpectedInput as exc:
        expected = sorted(_TOKEN_NAMES.get(t, t) for t in (getattr(exc, "expected", None) or []))
        what = f"; expected {' or '.join(expected)}" if expected else ""
        token = getattr(exc, "token", None)
        if isinstance(exc, UnexpectedEOF) or getattr(token, "type", None) == "$END":
            raise FormulaSyntaxError(f"formula ends too early{what}", len(text) + 1) from None
        found = text[exc.pos_in_stream:exc.pos_in_stream + 2].strip() or text[exc.pos_in_stream:][:1]
        raise FormulaSyntaxError(f"unexpected {found!r}{what}", exc.column) from None
    try:
        formula = _transformer()().transform(tree)
    except RecursionError:  # a long chain of binary operators
        raise FormulaSyntaxError(too_deep_message(), None) from None
    except Exception as exc:  # lark wraps transformer errors in VisitError
        inner = getattr(exc, "orig_exc", exc)
        if isinstance(inner, FormulaSyntaxError):
            raise inner from None
        if isinstance(inner, RecursionError):
            raise FormulaSyntaxError(too_deep_message(), None) from None
        raise
    if nesting_depth(formula) > MAX_NESTING:
        raise FormulaSyntaxError(too_deep_message(), None)
    return formula


def literals(formula: Formula) -> list[Literal]:
    """Every atom and AB literal in the formula, in order of appearance."""
    out: list[Literal] = []

    def walk(f: Formula) -> None:
        if isinstance(f, (Atom, Ab)):
            out.append(f)
        elif isinstance(f, Not):
            walk(f.arg)
        elif isinstance(f, (And, Or)):
            for a in f.args:
                walk(a)

    walk(formula)
    return out


def evaluate(formula: Formula, values: "dict[Literal, bool]") -> bool:
    """Truth value under a full assignment of the formula's literals (for checks and debugging)."""
    if isinstance(formula, Const):
        return formula.value
    if isinstance(formula, (Atom, Ab)):
        return values[formula]
    if isinstance(formula, Not):
        return not evaluate(formula.arg, values)
    if isinstance(formula, And):
        return all(evaluate(a, values) for a in formula.args)
    return any(evaluate(a, values) for a in formula.args)


def _nnf(f: Formula, positive: bool = True) -> Formula:
    """Push negations down to literals and flatten nested And/Or."""
    if isinstance(f, Const):
        return Const(f.value == positive)
    if isinstance(f, (Atom, Ab)):
        return f if positive else Not(f)
    if isinstance(f, Not):
        return _nnf(f.arg, not positive)
    kind = type(f) if positive else (Or if isinstance(f, And) else And)
    args: list[Formula] = []
    for a in f.args:
        n = _nnf(a, positive)
        if isinstance(n, kind):
            args.extend(n.args)
        else:
            args.append(n)
    return kind(tuple(args))


def to_cnf(formula: Formula, var_of: Callable[[Literal], int], new_var: Callable[[], int]) -> list[list[int]]:
    """Clauses equisatisfiable with ``formula`` over the variables ``var_of`` gives (see module doc)."""
    clauses: list[list[int]] = []

    def lit(f: Formula) -> int | None:
        """The literal for a literal formula, or None when f is compound."""
        if isinstance(f, (Atom, Ab)):
            return var_of(f)
        if isinstance(f, Not):
            return -var_of(f.arg)  # NNF: Not only wraps literals
        return None

    def clause_of(f: Formula) -> list[int] | None:
        """Clause for a disjunction; None if trivially true. Compound disjuncts get an auxiliary."""
        parts = f.args if isinstance(f, Or) else (f,)
        out: list[int] = []
        for part in parts:
            if isinstance(part, Const):
                if part.value:
                    return None
                continue
            x = lit(part)
            if x is None:  # a conjunction inside the disjunction: aux -> each conjunct
                x = new_var()
                for c in part.args:
                    add(c, guard=x)
            out.append(x)
        return out

    def add(f: Formula, guard: int | None = None) -> None:
        """Add clauses for `guard -> f` (or f itself when guard is None)."""
        if isinstance(f, And):
            for c in f.args:
                add(c, guard)
            return
        clause = clause_of(f)
        if clause is None:
            return
        clauses.append(clause if guard is None else [-guard, *clause])

    add(_nnf(formula))
    return clauses
