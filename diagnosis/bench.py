"""ISCAS-85 ``.bench`` netlists as diagnosis models (each gate a component, weak fault model).

Format (see ../shared/benchmarks/iscas85/README.md): ``INPUT(x)``, ``OUTPUT(y)``, ``y = TYPE(a, b, ...)``,
``#`` comments, gate types in any case, ``BUF``/``BUFF``. A gate is named after its output signal.
Weak fault model: ``!AB(g) -> (y <-> TYPE(inputs))``, nothing said about a faulty gate.
"""
from __future__ import annotations

import os
import re
from collections import namedtuple
from collections.abc import Mapping

from agentspeak.errors import SourceError
from agentspeak.source_text import read_source
from diagnosis.builder import ModelBuilder
from diagnosis.model import SystemModel
from diagnosis.simulation import netlist_code

GATE_TYPES = ("and", "nand", "or", "nor", "xor", "xnor", "not", "buf")
_DECL = re.compile(r"^(INPUT|OUTPUT)\s*\(\s*([^\s()]+)\s*\)$", re.IGNORECASE)
_GATE = re.compile(r"^([^\s=()]+)\s*=\s*([A-Za-z]+)\s*\(([^()]*)\)$")


Gate = namedtuple("Gate", "name type inputs line")            # inputs: tuple[str, ...]; line: in the file
Netlist = namedtuple("Netlist", "name source inputs outputs gates")
"""A parsed netlist; ``gates`` in topological order (inputs before the gates they feed). Named tuples, not
dataclasses: a netlist read for the first time should not pay ``dataclasses``' import (issue 23)."""


def parse_bench(path: str | os.PathLike, text: str | None = None) -> Netlist:
    """Read a .bench file; errors name file:line and what was expected."""
    path = os.fspath(path)
    text = read_source(path, "netlist") if text is None else text
    lines = text.splitlines()
    inputs: list[str] = []
    outputs: list[tuple[str, int]] = []
    gates: dict[str, Gate] = {}

    def fail(number: int, message: str) -> None:
        raise SourceError(message, file=path, line=number, source_line=lines[number - 1])

    for number, raw in enumerate(lines, 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        if m := _DECL.match(line):
            (inputs.append(m[2]) if m[1].upper() == "INPUT" else outputs.append((m[2], number)))
            continue
        m = _GATE.match(line)
        if not m:
            fail(number, "expected INPUT(x), OUTPUT(x) or 'y = TYPE(a, b, ...)'")
        kind = m[2].lower()
        kind = "buf" if kind == "buff" else kind
        if kind not in GATE_TYPES:
            fail(number, f"unknown gate type {m[2]!r}; expected one of {', '.join(GATE_TYPES)}, buff")
        args = tuple(a.strip() for a in m[3].split(",")) if m[3].strip() else ()
        if not args or any(not a for a in args):
            fail(number, f"gate {m[1]} needs a comma-separated list of input signals")
        if kind in ("not", "buf") and len(args) != 1:
            fail(number, f"{kind} takes one input, got {len(args)}")
        if m[1] in gates or m[1] in inputs:
            fail(number, f"signal {m[1]!r} is defined twice")
        gates[m[1]] = Gate(m[1], kind, args, number)

    defined = set(inputs) | set(gates)
    for gate in gates.values():
        for a in gate.inputs:
            if a not in defined:
                fail(gate.line, f"gate {gate.name} reads signal {a!r}, which no INPUT or gate defines")
    for name, number in outputs:
        if name not in defined:
            fail(number, f"OUTPUT({name}) is not defined by any INPUT or gate")
    return Netlist(os.path.splitext(os.path.basename(path))[0], path, tuple(inputs), tuple(n for n, _ in outputs),
                   _topological(gates, path, lines))


def _topological(gates: dict[str, Gate], path: str, lines: list[str]) -> tuple[Gate, ...]:
    order: list[Gate] = []
    state: dict[str, int] = {}  # 1 = on the stack, 2 = done
    for root in gates:
        stack = [(root, 0)]
        while stack:
            name, i = stack.pop()
            gate = gates.get(name)
            if gate is None or state.get(name) == 2:
                continue
            if i == 0:
                if state.get(name) == 1:
                    raise SourceError(f"combinational loop through {name}", file=path, line=gate.line,
                                      source_line=lines[gate.line - 1])
                state[name] = 1
            if i < len(gate.inputs):
                stack.append((name, i + 1))
                child = gate.inputs[i]
                if child in gates and state.get(child) != 2:
                    if state.get(child) == 1:
                        raise SourceError(f"combinational loop through {child}", file=path, line=gate.line,
                                          source_line=lines[gate.line - 1])
                    stack.append((child, 0))
            else:
                state[name] = 2
                order.append(gate)
    return tuple(order)


def gate_value(kind: str, values: list[bool]) -> bool:
    if kind in ("and", "nand"):
        out = all(values)
    elif kind in ("or", "nor"):
        out = any(values)
    elif kind in ("xor", "xnor"):
        out = sum(values) % 2 == 1
    else:  # not, buf
        out = values[0]
    return out != (kind in ("nand", "nor", "xnor", "not"))


def simulate(netlist: Netlist, inputs: Mapping[str, bool], flipped: frozenset[str] = frozenset()) -> dict[str, bool]:
    """Value of every signal; gates in ``flipped`` output the negation of their function (injected faults)."""
    values = dict(inputs)
    for gate in netlist.gates:
        v = gate_value(gate.type, [values[a] for a in gate.inputs])
        values[gate.name] = (not v) if gate.name in flipped else v
    return values


def netlist_model(netlist: Netlist) -> SystemModel:
    """CNF of the weak fault model; every signal is observable, gates are the components (file order)."""
    b = ModelBuilder(netlist.name, netlist.source, "netlist")
    for name in netlist.inputs:
        b.add_observable(name, "input")
    outputs = set(netlist.outputs)
    for gate in sorted(netlist.gates, key=lambda g: g.line):
        b.add_component(gate.name)
    for gate in netlist.gates:
        b.add_observable(gate.name, "output" if gate.name in outputs else "internal")
    readers: dict[str, list[str]] = {}
    for gate in netlist.gates:
        for a in dict.fromkeys(gate.inputs):
            readers.setdefault(a, []).append(gate.name)
    for gate in netlist.gates:
        b.output_of[gate.name] = gate.name
        b.readers[gate.name] = tuple(readers.get(gate.name, ()))
    b.gates = tuple((g.name, g.type, g.inputs) for g in netlist.gates)
    b.primary_inputs = netlist.inputs
    b.simulation = netlist_code(b.gates, b.primary_inputs)
    for gate in netlist.gates:
        ab = b.ab(gate.name)
        y = b.atom(gate.name)
        xs = [b.atom(a) for a in gate.inputs]
        for clause in _gate_clauses(gate.type, y, xs, b):
            b.add_clause([ab, *clause])
    return b.build()


def _gate_clauses(kind: str, y: int, xs: list[int], b: ModelBuilder) -> list[list[int]]:
    """Clauses of y <-> TYPE(xs) (without the health literal)."""
    if kind in ("nand", "nor", "xnor", "not"):
        y = -y
        kind = {"nand": "and", "nor": "or", "xnor": "xor", "not": "buf"}[kind]
    if kind == "buf":
        return [[-y, xs[0]], [y, -xs[0]]]
    if kind == "and":
        return [[-y, x] for x in xs] + [[y, *(-x for x in xs)]]
    if kind == "or":
        return [[y, -x] for x in xs] + [[-y, *xs]]
    clauses: list[list[int]] = []  # xor: chain through auxiliaries when more than two inputs
    acc = xs[0]
    for i, x in enumerate(xs[1:], 1):
        out = y if i == len(xs) - 1 else b.aux()
        clauses += [[-out, acc, x], [-out, -acc, -x], [out, -acc, x], [out, acc, -x]]
        acc = out
    return clauses


def load_bench_model(path: str | os.PathLike) -> SystemModel:
    return netlist_model(parse_bench(path))
