"""Diagnosis on the ISCAS-85 circuits: faultmas's engine vs a straightforward hitting-set baseline.

Instances: random primary inputs, k = 1..3 gates whose outputs are flipped (kept only if some output
differs from the fault-free circuit); observations are the primary inputs and outputs. Task: all
minimal diagnoses up to size 3. Baseline: python-sat's ``Hitman`` (sorted, i.e. smallest hitting sets
first) over conflicts, each conflict the core of a failed consistency check on the *same* CNF and
solver type; a hitting set that is consistent is a diagnosis and gets blocked. Both run in this
process, on the same instances, with the same per-instance time limit (60 s, the issue's target; 10 s in
quick mode). Also: minimum-cardinality
diagnosis for k = 10..30 injected faults on c7552 (ours only: the baseline has no such mode).
"""
from __future__ import annotations

import random
import statistics
import time
import zlib
from pathlib import Path

from pysat.examples.hitman import Hitman
from pysat.solvers import Solver

from diagnosis.bench import Netlist, parse_bench, simulate, netlist_model
from diagnosis.engine import DEFAULT_SOLVER, Deadline, Diagnoser, TimedOut
from diagnosis.model import SystemModel

ISCAS = Path(__file__).resolve().parents[1].parent / "shared" / "benchmarks" / "iscas85"
MAX_CARD = 3


def make_instances(netlist: Netlist, count: int, faults: list[int], seed: int) -> list[tuple[int, dict[str, bool]]]:
    """(k, observations) pairs whose injected faults show at some primary output."""
    rng = random.Random(seed)
    names = [g.name for g in netlist.gates]
    out = []
    for i in range(count):
        k = faults[i % len(faults)]
        while True:
            inputs = {x: rng.random() < 0.5 for x in netlist.inputs}
            bad = simulate(netlist, inputs, frozenset(rng.sample(names, k)))
            good = simulate(netlist, inputs)
            if any(bad[o] != good[o] for o in netlist.outputs):
                break
        out.append((k, {x: bad[x] for x in (*netlist.inputs, *netlist.outputs)}))
    return out


def baseline_diagnoses(model: SystemModel, solver: Solver, observations: dict[str, bool], max_card: int,
                       timeout: float) -> tuple[list[list[str]], bool]:
    """Reiter by hitting-set duality with pysat's Hitman; returns (diagnoses, complete)."""
    deadline = Deadline(timeout)
    obs = model.observation_literals(observations)
    found: list[list[str]] = []
    try:
        with Hitman(htype="sorted") as hitman:
            while True:
                hs = hitman.get()
                if hs is None or len(hs) > max_card:
                    return found, True
                bad = set(hs)
                assumptions = obs + [model.ab_var[c] if c in bad else -model.ab_var[c] for c in model.components]
                deadline.watch(solver)  # one timer per instance, as for the engine
                consistent = solver.solve_limited(assumptions=assumptions, expect_interrupt=True)
                if consistent is None or deadline.expired():
                    return found, False
                if consistent:
                    found.append(sorted(hs, key=model.components.index))
                    hitman.block(hs)
                    continue
                core = set(solver.get_core() or ())
                conflict = [c for c in model.components if -model.ab_var[c] in core]
                if not conflict:
                    return found, True  # inconsistent whatever is faulty
                hitman.hit(conflict)
    finally:
        deadline.release(solver)


def _median(xs: list[float]) -> str:
    return f"{statistics.median(xs):.3f}" if xs else "-"


def run(quick: bool) -> str:
    if not ISCAS.is_dir():
        return f"skipped: {ISCAS} not found"
    if quick:
        circuits, per_circuit, timeout = ["c432", "c880", "c1355", "c3540", "c7552"], 3, 10.0
        mincard_faults, mincard_count = [10, 20, 30], 3
    else:
        circuits = ["c432", "c499", "c880", "c1355", "c1908", "c2670", "c3540", "c5315", "c6288", "c7552"]
        per_circuit, timeout = 3, 60.0   # the target: no timeout at 60 s (c6288 excepted)
        mincard_faults, mincard_count = [10, 15, 20, 25, 30], 10
    rows = [f"all minimal diagnoses up to size {MAX_CARD}; {per_circuit} instances per circuit (k = 1..3 flipped"
            f" gates), limit {timeout:.0f} s each; seconds are medians (timeouts counted at the limit)",
            f"{'circuit':8} {'gates':>5} {'#diag':>7} {'ours s':>8} {'max':>7} {'t/o':>4} {'base s':>8} {'t/o':>4}"
            f" {'speedup':>8} agree"]
    for name in circuits:
        netlist = parse_bench(ISCAS / f"{name}.bench")
        model = netlist_model(netlist)
        ours = Diagnoser(model)
        base_solver = Solver(name=DEFAULT_SOLVER, bootstrap_with=[list(c) for c in model.clauses])
        t_ours, t_base, n_diag, to_ours, to_base, agree = [], [], [], 0, 0, True
        for k, obs in make_instances(netlist, per_circuit, [1, 2, 3], seed=zlib.crc32(name.encode())):
            result = ours.diagnose(obs, max_card=MAX_CARD, timeout=timeout)
            t_ours.append(min(result.seconds, timeout))
            to_ours += not result.complete
            n_diag.append(len(result.diagnoses))
            started = time.perf_counter()
            diags, complete = baseline_diagnoses(model, base_solver, obs, MAX_CARD, timeout)
            t_base.append(min(time.perf_counter() - started, timeout))
            to_base += not complete
            if complete and result.complete:
                agree &= sorted(map(tuple, diags)) == sorted(map(tuple, result.diagnoses))
        base_solver.delete()
        ours.close()
        speed = statistics.median(t_base) / max(statistics.median(t_ours), 1e-6)
        rows.append(f"{name:8} {len(model.components):5} {int(statistics.median(n_diag)):7} {_median(t_ours):>8}"
                    f" {max(t_ours):7.3f} {to_ours:4} {_median(t_base):>8} {to_base:4} {speed:7.1f}x"
                    f" {'yes' if agree else 'NO'}")

    netlist = parse_bench(ISCAS / "c7552.bench")
    ours = Diagnoser(netlist_model(netlist))
    rows.append("")
    rows.append(f"minimum-cardinality diagnosis on c7552 ({mincard_count} instances, k = {mincard_faults})")
    rows.append(f"{'k':>3} {'min card':>8} {'seconds':>8} complete")
    for k, obs in make_instances(netlist, mincard_count, mincard_faults, seed=7552):
        started = time.perf_counter()
        try:
            card, _ = ours.minimum_cardinality(obs, Deadline(60.0))
            first = time.perf_counter() - started
            rows.append(f"{k:3} {card:8} {first:8.3f} yes")
        except TimedOut:
            rows.append(f"{k:3} {'-':>8} {60.0:8.3f} timeout")
    ours.close()
    return "\n".join(rows)


if __name__ == "__main__":
    import sys
    print(run(quick="--quick" in sys.argv))
