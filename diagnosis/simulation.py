"""Consistency of many small fault sets at once, by bit-parallel simulation of a netlist.

In the weak fault model "exactly the gates in H are faulty" is consistent with fully observed primary
inputs iff some choice of the faulty gates' output values makes the circuit produce every observed
output. For |H| = m that is 2^m simulations; one Python integer carries them all as bit lanes, for a
whole batch of candidates side by side (candidate i owns lanes i*w .. i*w+w-1, w = max(8, 2^m), and in
lane a its j-th member outputs bit j of a). The netlist is compiled once into straight-line Python
(one line per gate: ``g = (inputs) & K[g] | P[g]``, K and P forcing the lanes where g is faulty), so a
batch of thousands of candidates costs about as much as a few SAT checks. Simulation yields no
conflicts: the engine uses it for the candidates it expects to be consistent, and SAT otherwise.
All-ones is -1 (Python integers are infinite two's complement), so ``~`` is the gate negation.
"""
from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping, Sequence
from types import CodeType

Gates = Sequence[tuple[str, str, tuple[str, ...]]]   # (output signal, type, input signals), topological
Compiled = Callable[[list[int], list[int], list[int]], list[int]]

_OPS = {"and": " & ", "nand": " & ", "or": " | ", "nor": " | ", "xor": " ^ ", "xnor": " ^ ",
        "not": "", "buf": ""}


def compile_netlist(gates: Gates, inputs: Sequence[str]) -> Compiled:
    """run(input lanes, K, P) -> lanes of every gate output (gate order), one Python line per gate."""
    return simulation_function(netlist_code(gates, inputs))


def simulation_function(code: CodeType) -> Compiled:
    """The ``run`` function defined by ``netlist_code``'s code."""
    namespace: dict = {}
    exec(code, namespace)  # generated from parsed gate types only
    return namespace["run"]


def netlist_code(gates: Gates, inputs: Sequence[str]) -> CodeType:
    """The compiled module that defines ``run`` (see ``compile_netlist``). Compiling is most of the cost (a tenth
    of a short ``faultmas diagnose`` on c1908), so a netlist's model keeps this code (``SystemModel.simulation``,
    kept between runs by ``netlist_cache``: ``marshal`` stores code objects as ``.pyc`` files do)."""
    var = {x: f"x{i}" for i, x in enumerate(inputs)}
    lines = ["def run(inp, K, P):"]
    if inputs:
        lines.append(f"    {', '.join(var[x] for x in inputs)}, = inp")
    for i, (name, kind, args) in enumerate(gates):
        expr = _OPS[kind].join(var[a] for a in args) or var[args[0]]
        if kind in ("nand", "nor", "xnor", "not"):
            expr = f"~({expr})"
        var[name] = f"g{i}"
        lines.append(f"    g{i} = ({expr}) & K[{i}] | P[{i}]")
    lines.append(f"    return [{', '.join(f'g{i}' for i in range(len(gates)))}]")
    return compile("\n".join(lines), "<netlist>", "exec")


class BatchSimulator:
    """One netlist under one observation set (all primary inputs observed: ``usable`` says so)."""

    def __init__(self, run: Compiled, position: Mapping[str, int], inputs: Sequence[str],
                 observations: Mapping[str, bool], index: Mapping[Hashable, int]) -> None:
        """``position`` of each gate (by output signal) in the compiled netlist; ``index`` maps the
        caller's key for each gate (e.g. its health variable) to the same positions."""
        self._run = run
        self._count = len(position)
        self._index = index
        self.usable = all(x in observations for x in inputs)
        self._inputs = [-1 if observations.get(x) else 0 for x in inputs]
        self._observed = [(position[name], -1 if value else 0) for name, value in observations.items()
                          if name in position]

    def consistent(self, candidates: Sequence[Sequence[Hashable]]) -> list[bool]:
        """For each candidate (gates as keys of ``index``, all of one size m): is exactly it faulty
        consistent with the observations?"""
        if not candidates:
            return []
        m = len(candidates[0])
        size = max(1, (1 << m) // 8)    # bytes per candidate
        n = len(candidates)
        masks: dict[int, bytearray] = {}
        forced: dict[int, bytearray] = {}
        index = self._index
        if size == 1:   # up to 3 members (the hitting-set tree's sizes): a byte per candidate, set by item
            lanes = [sum(1 << a for a in range(8) if a >> j & 1) for j in range(m)]
            for i, cand in enumerate(candidates):
                for j, g in enumerate(cand):
                    k = index[g]
                    mask = masks.get(k)
                    if mask is None:
                        mask = masks[k] = bytearray(n)
                        forced[k] = bytearray(n)
                    mask[i] = 255
                    forced[k][i] = lanes[j]
        else:
            patterns = [sum(1 << a for a in range(8 * size) if a >> j & 1).to_bytes(size, "little")
                        for j in range(m)]
            ones = b"\xff" * size
            for i, cand in enumerate(candidates):
                at = i * size
                for j, g in enumerate(cand):
                    k = index[g]
                    if k not in masks:
                        masks[k], forced[k] = bytearray(size * n), bytearray(size * n)
                    masks[k][at:at + size] = ones
                    forced[k][at:at + size] = patterns[j]
        keep = [-1] * self._count
        set_to = [0] * self._count
        for k, b in masks.items():
            keep[k] = ~int.from_bytes(b, "little")
            set_to[k] = int.from_bytes(forced[k], "little")
        values = self._run(self._inputs, keep, set_to)
        bad = 0
        for k, expected in self._observed:
            bad |= values[k] ^ expected
        ok = (~bad & ((1 << (8 * size * n)) - 1)).to_bytes(size * n, "little")
        if size == 1:
            return list(map(bool, ok))
        return [any(ok[i * size:(i + 1) * size]) for i in range(n)]
