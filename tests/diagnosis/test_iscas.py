"""ISCAS-85 netlists: injected faults are found, and both enumeration routes give the same ordered answer."""
from __future__ import annotations

import random

from diagnosis.bench import parse_bench, simulate, netlist_model
from diagnosis.engine import Deadline, Diagnoser


def instance(netlist, faults: int, seed: int) -> tuple[frozenset[str], dict[str, bool]]:
    rng = random.Random(seed)
    while True:
        inputs = {x: rng.random() < 0.5 for x in netlist.inputs}
        flipped = frozenset(rng.sample([g.name for g in netlist.gates], faults))
        bad, good = simulate(netlist, inputs, flipped), simulate(netlist, inputs)
        if any(bad[o] != good[o] for o in netlist.outputs):
            return flipped, {x: bad[x] for x in (*netlist.inputs, *netlist.outputs)}


def test_c432_tree_and_hitting_set_solver_routes_equal_the_bounded_route(iscas):
    netlist = parse_bench(iscas / "c432.bench")
    model = netlist_model(netlist)
    fast, direct = Diagnoser(model), Diagnoser(model)
    assert fast.monotone
    direct.monotone = False   # force the cardinality-bound route on the model's own solver
    order = {c: i for i, c in enumerate(model.components)}
    assert fast.model.readers        # post-dominators: diagnoses reached by dominance skip the SAT check
    for seed, faults in enumerate([1, 1, 2, 3]):
        flipped, obs = instance(netlist, faults, seed)
        result = fast.diagnose(obs, max_card=3)   # the hitting-set tree with batch simulation
        assert result.complete and result.diagnoses == direct.diagnose(obs, max_card=3).diagnoses
        via_solver = fast._conflict_levels(fast._base(obs), 3, Deadline(None), fast._structure(obs),
                                           fast._simulator(obs))   # post-dominator spreading, simulated variants
        assert list(via_solver) == result.diagnoses
        if faults == 1:
            assert sorted(flipped) in result.diagnoses        # a flipped gate alone explains what it did
        for d in result.diagnoses:
            assert d == sorted(d, key=order.__getitem__)
            assert fast.is_consistent(obs, d)
            assert not any(fast.is_consistent(obs, [x for x in d if x != y]) for y in d)   # minimal
        assert result.min_cardinality <= faults


def test_c880_minimum_cardinality_never_exceeds_the_injected_faults(iscas):
    netlist = parse_bench(iscas / "c880.bench")
    diagnoser = Diagnoser(netlist_model(netlist))
    for seed, faults in enumerate([4, 8]):
        flipped, obs = instance(netlist, faults, seed)
        k, one = diagnoser.minimum_cardinality(obs)
        assert 1 <= k <= faults and len(one) == k and diagnoser.is_consistent(obs, one)
        assert diagnoser.is_consistent(obs, sorted(flipped))
        result = diagnoser.diagnose(obs, min_card_only=True, max_count=50)
        assert result.min_cardinality == k and all(len(d) == k for d in result.diagnoses)
