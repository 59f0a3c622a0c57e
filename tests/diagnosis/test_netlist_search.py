"""The netlist shortcuts against brute force on random small circuits: the hitting-set tree with batch
simulation, post-dominator spreading on the solver route, the simulator itself, and the subset tests."""
from __future__ import annotations

import itertools

from hypothesis import HealthCheck, assume, given, settings, strategies as st

from diagnosis.bench import gate_value, netlist_model, parse_bench
from diagnosis.dominators import post_dominator_chains, reverse_topological
from diagnosis.engine import Diagnoser
from diagnosis.known import KnownDiagnoses
from diagnosis.simulation import BatchSimulator, compile_netlist

TYPES = ["and", "nand", "or", "nor", "xor", "xnor", "not", "buf"]


@st.composite
def netlists(draw):
    """Random .bench text: 2-4 inputs, 3-8 gates reading earlier signals, some gates as outputs."""
    inputs = [f"i{j}" for j in range(draw(st.integers(2, 4)))]
    signals, lines, gates = list(inputs), [f"INPUT({x})" for x in inputs], []
    for g in range(draw(st.integers(4, 10))):
        kind = draw(st.sampled_from(TYPES))
        arity = 1 if kind in ("not", "buf") else draw(st.integers(2, 3))
        args = draw(st.lists(st.sampled_from(signals), min_size=arity, max_size=arity, unique=True)
                    if len(signals) >= arity else st.just(signals[:1] * arity))
        name = f"g{g}"
        lines.append(f"{name} = {kind.upper()}({', '.join(args)})")
        signals.append(name)
        gates.append(name)
    read = {a for line in lines[len(inputs):] for a in line.split("(", 1)[1].rstrip(")").split(", ")}
    sinks = [g for g in gates if g not in read]
    outputs = sinks + draw(st.lists(st.sampled_from([g for g in gates if g in read] or gates), unique=True,
                                    max_size=2).map(lambda extra: [g for g in extra if g not in sinks]))
    text = "\n".join([*lines[:len(inputs)], *(f"OUTPUT({o})" for o in outputs), *lines[len(inputs):]])
    return parse_bench("random.bench", text)


def brute_consistent(netlist, observations, faulty) -> bool:
    """Some value of the unobserved inputs and of the faulty gates' outputs reproduces every observation."""
    free_inputs = [x for x in netlist.inputs if x not in observations]
    faulty = sorted(faulty)
    for bits in itertools.product([False, True], repeat=len(free_inputs) + len(faulty)):
        values = {**{x: observations[x] for x in netlist.inputs if x in observations},
                  **dict(zip(free_inputs, bits))}
        forced = dict(zip(faulty, bits[len(free_inputs):]))
        for gate in netlist.gates:
            values[gate.name] = forced[gate.name] if gate.name in forced else \
                gate_value(gate.type, [values[a] for a in gate.inputs])
        if all(values[name] == v for name, v in observations.items()):
            return True
    return False


def brute_minimal(netlist, observations, max_card):
    order = [g.name for g in sorted(netlist.gates, key=lambda g: g.line)]
    found = []
    for k in range(max_card + 1):
        for subset in itertools.combinations(order, k):
            if not any(set(d) <= set(subset) for d in found) and brute_consistent(netlist, observations, subset):
                found.append(subset)
    return [list(d) for d in found]


@st.composite
def observed(draw, hide: bool = True):
    """A random netlist and observations of it with 1-3 gates' outputs flipped (so usually wrong)."""
    netlist = draw(netlists())
    names = [g.name for g in netlist.gates]
    inputs = {x: draw(st.booleans()) for x in netlist.inputs}
    flipped = set(draw(st.lists(st.sampled_from(names), min_size=1, max_size=3, unique=True)))
    values = dict(inputs)
    for gate in netlist.gates:
        values[gate.name] = gate_value(gate.type, [values[a] for a in gate.inputs]) != (gate.name in flipped)
    obs = {x: values[x] for x in (*netlist.inputs, *netlist.outputs)}
    good = dict(inputs)
    for gate in netlist.gates:
        good[gate.name] = gate_value(gate.type, [good[a] for a in gate.inputs])
    assume(any(good[o] != obs[o] for o in netlist.outputs))   # the faults show
    if hide and draw(st.booleans()):
        obs.pop(netlist.inputs[0])    # the simulator needs every input: this takes the SAT-only path
    return netlist, obs


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(observed(), st.integers(2, 4))
def test_tree_and_solver_routes_equal_brute_force(instance, max_card):
    netlist, obs = instance
    diagnoser = Diagnoser(netlist_model(netlist))
    expected = brute_minimal(netlist, obs, max_card)
    result = diagnoser.diagnose(obs, max_card=max_card)   # bounds <= 3: tree; 4: hitting-set solver
    assert result.complete and result.diagnoses == expected, (obs, max_card)
    if max_card <= 3:  # the hitting-set solver route with post-dominator spreading on the same bound
        via_solver = list(diagnoser._conflict_levels(diagnoser._base(obs), max_card, _no_deadline(),
                                                     diagnoser._structure(obs), diagnoser._simulator(obs)))
        assert via_solver == expected


def _no_deadline():
    from diagnosis.engine import Deadline
    return Deadline(None)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(observed(hide=False))
def test_batch_simulation_agrees_with_brute_force_on_every_small_fault_set(instance):
    netlist, obs = instance
    model = netlist_model(netlist)
    names = [g.name for g in netlist.gates]
    position = {g: i for i, g in enumerate(names)}
    sim = BatchSimulator(compile_netlist(model.gates, model.primary_inputs), position, model.primary_inputs,
                         obs, position)
    assert sim.usable
    for m in (1, 2, 3, 4):     # 4: two bytes a candidate (the sliced path)
        candidates = [list(c) for c in itertools.combinations(names, m)]
        assert sim.consistent(candidates) == [brute_consistent(netlist, obs, c) for c in candidates]


@settings(max_examples=60, deadline=None)
@given(netlists(), st.lists(st.booleans(), min_size=8, max_size=8))
def test_post_dominator_chains_are_exactly_the_gates_every_observed_path_passes(netlist, observe_bits):
    readers: dict[str, list[str]] = {g.name: [] for g in netlist.gates}
    for g in netlist.gates:
        for a in dict.fromkeys(g.inputs):
            if a in readers:
                readers[a].append(g.name)
    observed = {g.name for g, bit in zip(netlist.gates, observe_bits) if bit} | set(netlist.outputs)
    chains = post_dominator_chains(reverse_topological(readers), readers, observed)

    def reaches_observed(start: str, avoid: str | None) -> bool:
        todo, seen = [start], set()
        while todo:
            node = todo.pop()
            if node == avoid or node in seen:
                continue
            seen.add(node)
            if node in observed:
                return True
            todo.extend(readers[node])
        return False

    for g in readers:
        if not reaches_observed(g, None):
            assert g not in chains
            continue
        dominators = [d for d in readers if d != g and g not in observed and not reaches_observed(g, d)]
        assert chains[g][0] == g and sorted(chains[g][1:]) == sorted(dominators)


@given(st.lists(st.frozensets(st.integers(0, 6), min_size=1, max_size=3), max_size=8),
       st.lists(st.integers(0, 6), max_size=3, unique=True))
def test_known_diagnoses_subset_tests(diagnoses, node):
    known = KnownDiagnoses()
    for d in diagnoses:
        known.add(d)
    assert known.within(node) == any(d <= set(node) for d in diagnoses)
    if not known.within(node):
        assert known.completing(node) == {x for x in range(7) if x not in node and known.within([*node, x])}
