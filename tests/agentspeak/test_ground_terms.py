"""The hand-written ground-term reader must build exactly what the grammar builds, or step aside."""
from __future__ import annotations

from hypothesis import example, given, settings, strategies as st

from agentspeak.ground_terms import _KEYWORDS, read_ground_term
from agentspeak.parser import parse_literal, parse_program
from agentspeak.terms import Cons, Literal, to_str

import pytest


def _full_parse(text: str):
    """The grammar's reading of one term (what parse_literal did before the fast reader)."""
    program = parse_program(f"term__({text}).", "<term>")
    return program.beliefs[0].args[0] if program.beliefs else program.rules[0].head.args[0]


def _same(a, b) -> bool:
    if type(a) is not type(b):
        return False
    if type(a) is Literal:
        return (a.functor == b.functor and a.neg == b.neg and len(a.args) == len(b.args)
                and all(_same(x, y) for x, y in zip(a.args, b.args))
                and (a.annots is None) == (b.annots is None)
                and all(_same(x, y) for x, y in zip(a.annots or (), b.annots or ())))
    if type(a) is Cons:
        return _same(a.head, b.head) and _same(a.tail, b.tail)
    return a == b


@pytest.mark.parametrize("text", [
    'm(12,"abc")', "p", "'Quoted atom'", "~p(1)[a,b]", "p[source(bob),a,a]", "[]", "[1,[2,3],x]",
    "f(-3, -2.5, 1.0, 1e3, 2.5E-3)", 'say("a\\"b\\nc\\t")', "p(a)[]", "notx(divide, modes)",
    "  pos( 3 , 4 )  ", "42", '"text"', 'm("a,b", - 3, x)', 'p( -1e2 )',
    'm("a\\\\", "b\\"c", 3)', 'm( "x" , "" ,y )', 'm(7,"' + "x" * 4096 + '")', 'm("(a)", "[b]", "\'c\'")',
])
def test_reader_builds_what_the_grammar_builds(text: str) -> None:
    term = read_ground_term(text)
    assert term is not None, text
    assert _same(term, _full_parse(text)), text


@pytest.mark.parametrize("text", [
    "p(X)", "p(_)", "1 + 2", "p(1-2)", "not p", "p(3 div 2)", ".print(a)", "a.b", "{+!g <- true}",
    "p(a", "p()", "[a|T]", "p // comment", "true", "- x", "p(a) q", "",
    'm("abc)', 'm("a"b)', 'm("a" 1)', 'm(1,)', 'm("a\\")', 'm("a") x',
])
def test_reader_steps_aside_outside_its_subset(text: str) -> None:
    assert read_ground_term(text) is None


def test_syntax_errors_still_come_from_the_full_parser() -> None:
    with pytest.raises(ValueError, match="term"):
        parse_literal("p(a")


_atoms = st.from_regex(r"[a-z][a-zA-Z0-9_]{0,6}", fullmatch=True)
_leaves = st.one_of(
    st.integers(-10 ** 6, 10 ** 6), st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False),
    st.text(alphabet=st.characters(blacklist_categories=("Cs",), blacklist_characters="\n\\\""), max_size=8),
    _atoms.map(Literal))


def _extend(children):
    return st.one_of(
        st.builds(lambda f, args: Literal(f, tuple(args)), _atoms, st.lists(children, min_size=1, max_size=3)),
        st.builds(lambda f, args, ann, neg: Literal(f, tuple(args), tuple(ann) or None, neg),
                  _atoms, st.lists(children, max_size=2), st.lists(children, max_size=2), st.booleans()),
        st.lists(children, max_size=3).map(lambda xs: _cons(xs)))


def _cons(xs):
    from agentspeak.terms import make_list
    return make_list(xs)


@settings(max_examples=150, deadline=None)
@given(st.recursive(_leaves, _extend, max_leaves=8))
def test_printed_ground_terms_read_back_as_the_grammar_reads_them(term) -> None:
    text = to_str(term)
    fast = read_ground_term(text)
    full = _full_parse(text)
    assert fast is None or _same(fast, full), text


_flat_strings = st.text(alphabet=st.sampled_from('ab ,()[]\'"\\\\n\t'), max_size=12)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.one_of(st.integers(-99, 99), _atoms.map(Literal), _flat_strings), min_size=1, max_size=4),
       st.sampled_from(["", " ", "\n"]))
@example([Literal("if")], "")
def test_flat_structures_with_awkward_strings_read_as_the_grammar_reads_them(args, blank) -> None:
    text = f"{blank}m({blank}{(',' + blank).join(to_str(a) for a in args)}){blank}"
    fast = read_ground_term(text)
    if fast is None:   # words the grammar reserves (if, div, not...) are left to it (hypothesis found m(if))
        assert any(isinstance(a, Literal) and a.functor in _KEYWORDS for a in args), text
        return
    assert _same(fast, _full_parse(text)), text
