"""The minimal diagnoses found so far in one query, grouped by size for fast subset tests.

A candidate is a new minimal diagnosis only if no known one is a subset of it. Diagnoses are small
and few sizes occur, so testing the candidate's subsets of those sizes is usually far cheaper than
scanning every known diagnosis; the scan is used when it is not.
"""
from __future__ import annotations

import itertools
from collections.abc import Iterable, Sequence


class KnownDiagnoses:
    def __init__(self) -> None:
        self.by_size: dict[int, set[frozenset[int]]] = {}
        self.count = 0
        self._partners: dict[frozenset[int], set[int]] = {}  # D - {x} -> those x, for known D

    def add(self, diagnosis: Iterable[int]) -> None:
        d = frozenset(diagnosis)
        group = self.by_size.setdefault(len(d), set())
        if d not in group:
            group.add(d)
            self.count += 1
            for x in d:
                self._partners.setdefault(d - {x}, set()).add(x)

    def completing(self, node: Sequence[int]) -> set[int]:
        """The x for which node + [x] contains a known diagnosis that node alone does not: one
        look-up per subset of the (small) node instead of one subset test per x."""
        out: set[int] = set()
        for r in range(len(node) + 1):
            for sub in itertools.combinations(node, r):
                found = self._partners.get(frozenset(sub))
                if found:
                    out |= found
        return out

    def within(self, candidate: Sequence[int]) -> bool:
        """Is some known diagnosis a subset of (or equal to) the candidate?"""
        from math import comb    # here: only the hitting-set route (bounds over 3) asks (start-up: issue 23)

        n = len(candidate)
        sizes = [s for s in self.by_size if s <= n]
        if sum(comb(n, s) for s in sizes) <= self.count:
            return any(frozenset(sub) in self.by_size[s] for s in sizes
                       for sub in itertools.combinations(candidate, s))
        whole = frozenset(candidate)
        return any(d <= whole for s in sizes for d in self.by_size[s])

    def within_adding(self, x: int, chosen: Sequence[int]) -> bool:
        """Is some known diagnosis a subset of chosen + [x] that contains x? (chosen itself was
        tested before x was added, so these are the only new subsets.)"""
        for s, group in self.by_size.items():
            if 1 <= s <= len(chosen) + 1:
                if s == 1:
                    if frozenset((x,)) in group:
                        return True
                    continue
                for sub in itertools.combinations(chosen, s - 1):
                    if frozenset((x, *sub)) in group:
                        return True
        return False
