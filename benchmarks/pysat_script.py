"""The plain python-sat script faultmas's ``diagnose`` is compared with, whole process (bench_startup).

    python benchmarks/pysat_script.py CIRCUIT.bench OBS.json MAX_CARD     # prints the diagnoses as JSON

What a researcher writes in an afternoon with python-sat alone (stdlib + pysat, no faultmas import): the
weak-fault model of the netlist in CNF (Tseitin, ``ab_g or out_g <-> TYPE(inputs)``), then Reiter's
diagnoses by hitting-set duality with pysat's ``Hitman`` (smallest first) over conflicts, each the core of a
failed consistency check: the algorithm of ``benchmarks/bench_diagnosis.baseline_diagnoses``.
"""
from __future__ import annotations

import json
import re
import sys

from pysat.examples.hitman import Hitman
from pysat.formula import IDPool
from pysat.solvers import Solver


def read_bench(path: str) -> tuple[list[str], list[str], list[tuple[str, str, list[str]]]]:
    inputs, outputs, gates = [], [], []
    for raw in open(path, encoding="utf-8"):
        line = raw.split("#", 1)[0].strip()
        if m := re.match(r"(INPUT|OUTPUT)\s*\(\s*(\S+?)\s*\)$", line, re.I):
            (inputs if m[1].upper() == "INPUT" else outputs).append(m[2])
        elif m := re.match(r"(\S+)\s*=\s*(\w+)\s*\((.*)\)$", line):
            gates.append((m[1], m[2].lower().replace("buff", "buf"), [a.strip() for a in m[3].split(",")]))
    return inputs, outputs, gates


def gate_clauses(kind: str, out: int, ins: list[int]) -> list[list[int]]:
    """Clauses of ``out <-> kind(ins)``."""
    if kind in ("buf", "not"):
        sign = 1 if kind == "buf" else -1
        return [[-out, sign * ins[0]], [out, -sign * ins[0]]]
    if kind in ("and", "nand", "or", "nor"):
        o = out if kind in ("and", "or") else -out
        if kind in ("and", "nand"):
            return [[-o, i] for i in ins] + [[o] + [-i for i in ins]]
        return [[o, -i] for i in ins] + [[-o] + ins]
    # xor / xnor: a chain of 2-input xors through fresh variables
    acc = ins[0]
    clauses: list[list[int]] = []
    for k, i in enumerate(ins[1:], 1):
        last = k == len(ins) - 1
        t = (out if kind == "xor" else -out) if last else POOL.id(("xor", out, k))
        clauses += [[-t, acc, i], [-t, -acc, -i], [t, -acc, i], [t, acc, -i]]
        acc = t
    return clauses


POOL = IDPool()


def main() -> int:
    bench, obs_file, max_card = sys.argv[1], sys.argv[2], int(sys.argv[3])
    inputs, outputs, gates = read_bench(bench)
    observations = json.load(open(obs_file, encoding="utf-8"))
    ab = {name: POOL.id(("ab", name)) for name, _, _ in gates}
    solver = Solver(name="glucose4")
    for name, kind, args in gates:
        for clause in gate_clauses(kind, POOL.id(name), [POOL.id(a) for a in args]):
            solver.add_clause([ab[name], *clause])
    obs = [POOL.id(n) if v else -POOL.id(n) for n, v in observations.items()]
    found = []
    with Hitman(htype="sorted") as hitman:
        while True:
            hs = hitman.get()
            if hs is None or len(hs) > max_card:
                break
            bad = set(hs)
            if solver.solve(assumptions=obs + [ab[g] if g in bad else -ab[g] for g in ab]):
                found.append(sorted(hs))
                hitman.block(hs)
                continue
            core = set(solver.get_core() or ())
            conflict = [g for g in ab if -ab[g] in core]
            if not conflict:
                break
            hitman.hit(conflict)
    print(json.dumps(found))
    return 0


if __name__ == "__main__":
    sys.exit(main())
