"""Consistency of many small fault sets at once, by bit-parallel simulation of a netlist.

In the weak fault model "exactly the gates in H are faulty" is consistent with fully observed primary
inputs iff some choice of the faulty gates' output values makes the circuit produce every observed
output. For |H| = m that is 2^m simulations; one Python integer carries them all as bit lanes, for a
whole batch of candidates side by side (lane block i*2^m..(i+1)*2^m-1 belongs to candidate i). Only
the gates downstream of some candidate's members are simulated; the rest keep their fault-free value.
A batch of a thousand candidates costs about as much as a few SAT checks, but yields no conflicts:
the engine uses it for candidates it expects to be consistent and asks the SAT solver otherwise.
"""
from __future__ import annotations

from typing import Mapping, Sequence

Gates = Sequence[tuple[str, str, tuple[str, ...]]]   # (output signal, type, input signals), topological


class BatchSimulator:
    """One netlist under one observation set (all primary inputs observed: ``usable`` says so)."""

    def __init__(self, gates: Gates, readers: Mapping[str, Sequence[str]], inputs: Sequence[str],
                 observations: Mapping[str, bool]) -> None:
        self._gates = {g[0]: g for g in gates}
        self._rank = {g[0]: i for i, g in enumerate(gates)}
        self._readers = readers
        self.usable = all(x in observations for x in inputs)
        self._observed = {name: bool(v) for name, v in observations.items() if name in self._gates}
        self._good: dict[str, bool] = {x: bool(observations[x]) for x in inputs} if self.usable else {}
        if self.usable:
            for name, kind, args in gates:
                self._good[name] = _gate(kind, [self._good[a] for a in args], True)

    def consistent(self, candidates: Sequence[Sequence[str]]) -> list[bool]:
        """For each candidate (gate names, all of one size m), is exactly it faulty consistent?"""
        if not candidates:
            return []
        m = len(candidates[0])
        size = max(1, (1 << m) // 8)    # bytes per candidate: at least 8 lanes, lane a sets member j to bit j of a
        n = len(candidates)
        full = (1 << (8 * size * n)) - 1
        patterns = [sum(1 << a for a in range(8 * size) if a >> j & 1).to_bytes(size, "little") for j in range(m)]
        ones = b"\xff" * size
        masks: dict[str, bytearray] = {}
        forced: dict[str, bytearray] = {}
        for i, cand in enumerate(candidates):
            at = i * size
            for j, g in enumerate(cand):
                if g not in masks:
                    masks[g], forced[g] = bytearray(size * n), bytearray(size * n)
                masks[g][at:at + size] = ones
                forced[g][at:at + size] = patterns[j]
        keep = {g: ~int.from_bytes(b, "little") for g, b in masks.items()}
        set_to = {g: int.from_bytes(b, "little") for g, b in forced.items()}
        values: dict[str, int] = {}
        good = self._good
        for name in self._cone(masks):
            _, kind, args = self._gates[name]
            v = _gate(kind, [values[a] if a in values else (full if good[a] else 0) for a in args], full)
            if name in keep:
                v = (v & keep[name]) | set_to[name]
            values[name] = v
        bad = 0
        for name, observed in self._observed.items():
            v = values.get(name)
            if v is None:
                if good[name] != observed:
                    return [False] * n   # a mismatch no candidate reaches
                continue
            bad |= v ^ (full if observed else 0)
        ok = (full & ~bad).to_bytes(size * n, "little")
        if size == 1:
            return [b != 0 for b in ok]
        return [any(ok[i * size:(i + 1) * size]) for i in range(n)]

    def _cone(self, roots: Mapping[str, int]) -> list[str]:
        """The gates downstream of the roots (roots included), in topological order."""
        seen = set(roots)
        todo = list(roots)
        while todo:
            for r in self._readers.get(todo.pop(), ()):
                if r not in seen:
                    seen.add(r)
                    todo.append(r)
        return sorted(seen, key=self._rank.__getitem__)


def _gate(kind: str, ins: list, one):
    """Gate function on bools (one=True) or on bit lanes (one = all lanes set)."""
    if kind in ("and", "nand"):
        v = ins[0]
        for x in ins[1:]:
            v &= x
    elif kind in ("or", "nor"):
        v = ins[0]
        for x in ins[1:]:
            v |= x
    elif kind in ("xor", "xnor"):
        v = ins[0]
        for x in ins[1:]:
            v ^= x
    else:  # not, buf
        v = ins[0]
    return v ^ one if kind in ("nand", "nor", "xnor", "not") else v
