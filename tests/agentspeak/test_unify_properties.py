"""Property tests for unification (agentspeak.unify) over randomly generated terms."""
from __future__ import annotations

from hypothesis import given, settings, strategies as st

from agentspeak.terms import Literal, Var, make_list, resolve, to_str
from agentspeak.unify import unify

VARS = [Var(n) for n in ("X", "Y", "Z", "W")]
ATOMS = ["a", "b", "c"]


def _terms(annots: bool):
    leaves = st.one_of(
        st.sampled_from(VARS),
        st.sampled_from(ATOMS).map(Literal),
        st.integers(-3, 3),
        st.sampled_from(["s", "t"]),
    )

    def extend(children):
        struct = st.builds(lambda f, args: Literal(f, tuple(args)), st.sampled_from(["f", "g"]),
                           st.lists(children, min_size=1, max_size=3))
        lists = st.lists(children, max_size=3).map(make_list)
        return st.one_of(struct, lists)
    return st.recursive(leaves, extend, max_leaves=8)


plain_terms = _terms(annots=False)
ground_annots = st.lists(st.one_of(st.sampled_from(ATOMS).map(Literal),
                                   st.builds(lambda a: Literal("source", (Literal(a),)), st.sampled_from(ATOMS))),
                         max_size=3)


def _try(a, c):
    b: dict = {}
    return unify(a, c, b, []), b


def _occurs_free(b: dict) -> bool:
    """No variable is bound to a term that (after resolving) still contains it."""
    for v in b:
        seen, stack = 0, [b[v]]
        while stack:
            seen += 1
            if seen > 10_000:
                return False
            t = stack.pop()
            while isinstance(t, Var) and t in b:
                if t is v:
                    return False
                t = b[t]
            if isinstance(t, Literal):
                stack.extend(t.args)
            elif hasattr(t, "head"):
                stack.extend((t.head, t.tail))
    return True


@settings(max_examples=200, deadline=None)
@given(plain_terms, plain_terms)
def test_success_is_symmetric_without_annotations(a, c):
    assert _try(a, c)[0] == _try(c, a)[0]


@settings(max_examples=200, deadline=None)
@given(plain_terms, plain_terms)
def test_unifier_makes_both_sides_equal(a, c):
    ok, b = _try(a, c)
    if ok and _occurs_free(b):
        assert to_str(resolve(a, b)) == to_str(resolve(c, b))


@settings(max_examples=200, deadline=None)
@given(plain_terms, plain_terms)
def test_applying_an_occurs_free_unifier_twice_changes_nothing(a, c):
    ok, b = _try(a, c)
    if ok and _occurs_free(b):
        once = resolve(a, b)
        assert to_str(resolve(once, b)) == to_str(once)


@settings(max_examples=200, deadline=None)
@given(plain_terms)
def test_a_term_unifies_with_itself_binding_nothing_new(a):
    ok, b = _try(a, a)
    assert ok and b == {}


@settings(max_examples=200, deadline=None)
@given(ground_annots, ground_annots)
def test_annotations_of_the_left_side_must_be_a_subset_of_the_right(left, right):
    lhs = Literal("p", (Literal("a"),), tuple(left) or None)
    rhs = Literal("p", (Literal("a"),), tuple(right) or None)
    subset = {to_str(t) for t in left} <= {to_str(t) for t in right}
    assert _try(lhs, rhs)[0] == subset


def test_annotation_direction_concrete():
    with_src = Literal("price", (Var("A"), Var("V")), (Literal("source", (Literal("bob"),)),))
    bare = Literal("price", (Var("B"), Var("W")))
    assert not _try(with_src, bare)[0]
    assert _try(bare, with_src)[0]
