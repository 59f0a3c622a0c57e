"""The diagnoser against brute force on random small models, and its query semantics."""
from __future__ import annotations

import itertools

from hypothesis import HealthCheck, given, settings, strategies as st

from diagnosis.engine import Diagnoser
from diagnosis.formula import Ab, Atom, evaluate, parse_formula
from diagnosis.loader import load_model
from diagnosis.system_yaml import load_system
from diagnosis.yaml_source import YamlSource

COMPONENTS = ["c0", "c1", "c2", "c3"]
OBSERVATIONS = ["o0", "o1", "o2"]
VARIABLES = ["v0", "v1"]


def consistent(formulas, observations, faulty) -> bool:
    """Brute force: some assignment of the internal variables satisfies every formula."""
    fixed = {Atom(o): v for o, v in observations.items()} | {Ab(c): c in faulty for c in COMPONENTS}
    free = [Atom(o) for o in OBSERVATIONS if o not in observations] + [Atom(v) for v in VARIABLES]
    for bits in itertools.product([False, True], repeat=len(free)):
        values = fixed | dict(zip(free, bits))
        if all(evaluate(f, values) for f in formulas):
            return True
    return False


def brute_minimal_diagnoses(formulas, observations, max_card):
    diagnoses = []
    for k in range(max_card + 1):
        for subset in itertools.combinations(COMPONENTS, k):
            if any(set(d) <= set(subset) for d in diagnoses):
                continue
            if consistent(formulas, observations, set(subset)):
                diagnoses.append(subset)
    return [list(d) for d in diagnoses]


atom = st.sampled_from([f"AB({c})" for c in COMPONENTS] + OBSERVATIONS + VARIABLES)
formula = st.recursive(atom, lambda sub: st.one_of(
    st.builds(lambda a: f"!({a})", sub),
    st.builds(lambda a, b, op: f"({a}) {op} ({b})", sub, sub, st.sampled_from(["&", "|", "->", "<->"]))),
    max_leaves=5)
healthy_rule = st.builds(lambda c, body: f"!AB({c}) -> ({body})", st.sampled_from(COMPONENTS), formula)
models = st.lists(st.one_of(healthy_rule, healthy_rule, formula), min_size=1, max_size=6)
observation_sets = st.dictionaries(st.sampled_from(OBSERVATIONS), st.booleans())


def build(rules):
    text = "system: random\ncomponents: [c0, c1, c2, c3]\nobservations: [o0, o1, o2]\nvariables: [v0, v1]\n" \
           "behaviour:\n" + "".join(f"  - \"{r}\"\n" for r in rules)
    return load_system(YamlSource("random.yaml", text))


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(models, st.lists(observation_sets, min_size=1, max_size=3), st.integers(0, 4))
def test_minimal_diagnoses_equal_brute_force_on_one_persistent_solver(rules, queries, max_card):
    model = build(rules)
    formulas = [parse_formula(r) for r in rules]
    diagnoser = Diagnoser(model)
    for observations in queries:  # several queries on one solver: nothing may leak between them
        expected = brute_minimal_diagnoses(formulas, observations, max_card)
        result = diagnoser.diagnose(observations, max_card=max_card)
        assert result.complete
        assert result.diagnoses == expected, (rules, observations)
        assert result.min_cardinality == (len(expected[0]) if expected else None)
        for d in result.diagnoses:
            assert diagnoser.is_consistent(observations, d)
        full = brute_minimal_diagnoses(formulas, observations, len(COMPONENTS))
        k, one = diagnoser.minimum_cardinality(observations)
        assert k == (len(full[0]) if full else None)
        assert one is None or list(one) in full
        minimum = [d for d in full if len(d) == k] if full and k else []
        assert diagnoser.possibly_faulty(observations) == [c for c in COMPONENTS if any(c in d for d in minimum)]


def test_levels_stream_in_size_order_and_sorted_by_component_order(data_dir):
    diagnoser = Diagnoser(load_model(data_dir / "c17.bench"))
    # all-ones inputs give G22=1, G23=0; observing G23=1 needs a fault in G23's cone
    obs = {"G1gat": True, "G2gat": True, "G3gat": True, "G6gat": True, "G7gat": True,
           "G22gat": True, "G23gat": True}
    stream = list(diagnoser.minimal_diagnoses(obs, max_card=3))
    assert [len(d) for d in stream] == sorted(len(d) for d in stream)
    order = diagnoser.model.components
    singles = [d for d in stream if len(d) == 1]
    assert singles == sorted(singles, key=lambda d: order.index(d[0]))
    assert ["G23gat"] in stream


def test_count_and_time_limits_report_an_incomplete_answer(data_dir):
    diagnoser = Diagnoser(load_model(data_dir / "c17.bench"))
    obs = {"G1gat": True, "G2gat": True, "G3gat": True, "G6gat": True, "G7gat": True,
           "G22gat": False, "G23gat": True}
    full = diagnoser.diagnose(obs, max_card=3)
    assert full.complete and len(full.diagnoses) > 2
    cut = diagnoser.diagnose(obs, max_card=3, max_count=2)
    assert not cut.complete and cut.diagnoses == full.diagnoses[:2]
    expired = diagnoser.diagnose(obs, max_card=3, timeout=0.0)
    assert not expired.complete and expired.diagnoses == []
    assert diagnoser.diagnose(obs, max_card=3).diagnoses == full.diagnoses  # the solver is left clean


def test_contradictory_observations_have_no_diagnosis(write):
    model = load_model(write("m.yaml", "system: s\ncomponents: [c]\nobservations: [a]\nassumptions: [\"a\"]\n"))
    result = Diagnoser(model).diagnose({"a": False})
    assert result.diagnoses == [] and result.complete and not result.consistent_with_model
    assert result.min_cardinality is None


plain_atom = st.sampled_from(OBSERVATIONS + VARIABLES)
plain_formula = st.recursive(plain_atom, lambda sub: st.one_of(
    st.builds(lambda a: f"!({a})", sub),
    st.builds(lambda a, b, op: f"({a}) {op} ({b})", sub, sub, st.sampled_from(["&", "|", "->", "<->"]))),
    max_leaves=5)
weak_models = st.lists(st.builds(lambda c, body: f"!AB({c}) -> ({body})", st.sampled_from(COMPONENTS),
                                 plain_formula), min_size=1, max_size=6)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(weak_models, st.lists(observation_sets, min_size=1, max_size=3), st.integers(0, 4))
def test_weak_fault_models_take_the_conflict_route_and_agree_with_brute_force(rules, queries, max_card):
    model = build(rules)
    formulas = [parse_formula(r) for r in rules]
    diagnoser = Diagnoser(model)
    assert diagnoser.monotone
    for observations in queries:
        expected = brute_minimal_diagnoses(formulas, observations, max_card)
        assert diagnoser.diagnose(observations, max_card=max_card).diagnoses == expected, (rules, observations)
        full = brute_minimal_diagnoses(formulas, observations, len(COMPONENTS))
        k = len(full[0]) if full else None
        assert diagnoser.minimum_cardinality(observations)[0] == k
        minimum = [d for d in full if len(d) == k] if full and k else []
        assert diagnoser.diagnose(observations, min_card_only=True).diagnoses == (minimum if k else full[:1])
        assert diagnoser.possibly_faulty(observations) == [c for c in COMPONENTS if any(c in d for d in minimum)]
