"""All minimal diagnoses of a monotone model up to a small size, by a level-wise hitting-set tree.

Reiter's HS-tree, breadth first, with sets as nodes: a node S (|S| = d) that is not a diagnosis gets
a *label*, a conflict S does not hit, and its children are S + x for x in the label. Every minimal
diagnosis D is reached (each label holds some member of D) and, once all levels below are done, a
consistent node that contains no known diagnosis is minimal. What makes it fast here:

* conflicts are bit sets: ``hits[v]`` has bit i set when component v is in conflict i, so "which
  known conflicts does S miss" is one OR over S's members;
* a node that misses some known conflict is not consistent: it gets that conflict as its label
  without any check, so only nodes hitting every known conflict are checked at all;
* those are checked in batches (``simulate``: bit-parallel simulation on netlists); only the ones
  found inconsistent below the last level go to the SAT solver, for a new conflict to branch on;
* on the last level a child S + x is made only if x lies in every conflict S misses (one subset
  test per group of members lying in exactly the same conflicts), so every node made there is
  a hitting set of everything known and no SAT call is needed on that level at all.

Costs grow with the product of label sizes, so this is meant for small bounds (the engine uses it up
to ``engine._TREE_LIMIT``); larger bounds take the hitting-set solver route.
"""
from __future__ import annotations

import bisect
from collections.abc import Callable, Iterator, Sequence

from diagnosis.known import KnownDiagnoses

Check = Callable[[list[int]], "list[int] | None"]
Simulate = Callable[[list[list[int]]], "list[bool] | None"]
_BATCH = 4096   # nodes simulated together
_LEARN = 8      # failures per batch on the last level sent to the SAT solver for their conflicts


class Conflicts:
    """Conflicts (sets of health variables, not all healthy) as bit sets."""

    def __init__(self) -> None:
        self.sets: list[list[int]] = []
        self.hits: dict[int, int] = {}
        self.all = 0
        self._order: list[tuple[int, int, list[int]]] = []   # (size, bit, members), smallest first
        self._groups: dict[int, list[tuple[int, list[int]]]] = {}

    def add(self, conflict: Sequence[int]) -> None:
        bit = 1 << len(self.sets)
        self.sets.append(list(conflict))
        for v in conflict:
            self.hits[v] = self.hits.get(v, 0) | bit
        self.all |= bit
        bisect.insort(self._order, (len(conflict), bit, self.sets[-1]), key=lambda e: e[0])
        self._groups.clear()

    def missed(self, node: Sequence[int]) -> int:
        """Bits of the conflicts that no member of node is in."""
        hit = 0
        hits = self.hits
        for v in node:
            hit |= hits.get(v, 0)
        return self.all & ~hit

    def label(self, missed: int) -> list[int]:
        """The smallest conflict among the missed ones."""
        for _size, bit, members in self._order:
            if missed & bit:
                return members
        raise ValueError("no conflict is missed")

    def completions(self, missed: int) -> list[int]:
        """Members lying in every missed conflict: the single elements that complete a hitting set."""
        members = self.label(missed)
        key = id(members)
        groups = self._groups.get(key)
        if groups is None:  # members of this conflict grouped by the conflicts they are in
            by_sig: dict[int, list[int]] = {}
            for v in members:
                by_sig.setdefault(self.hits[v], []).append(v)
            groups = self._groups[key] = list(by_sig.items())
        out: list[int] = []
        for sig, group in groups:
            if not missed & ~sig:
                out.extend(group)
        return out


def tree_levels(limit: int, check: Check, simulate: Simulate, known: KnownDiagnoses,
                record: Callable[[list[int]], None], tick: Callable[[], None]) -> Iterator[int]:
    """Run the levels 0..limit; ``record`` gets each minimal diagnosis (after ``known.add``), the
    generator yields each level's number once that level is complete. ``tick`` raises on timeout."""
    conflicts = Conflicts()
    root = check([])
    if root == []:
        return  # the observations contradict the model whatever is faulty: no diagnosis at all
    if root is None:
        known.add([])
        record([])
        yield 0
        return
    conflicts.add(root)
    yield 0
    frontier: list[tuple[int, ...]] = [()]
    for d in range(1, limit + 1):
        last = d == limit
        following: list[tuple[int, ...]] = []   # the inconsistent nodes of this level

        def settle(batch: list[list[int]]) -> None:
            """Check nodes that hit every known conflict: diagnoses are recorded, the others are
            labelled by a conflict (learned from the SAT solver when none known tells them apart).
            On the last level a few failures still go to the SAT solver: their conflicts spare
            the simulation of later nodes."""
            if len(conflicts.sets) > known_conflicts[0]:  # conflicts learned since these were made
                known_conflicts[0] = len(conflicts.sets)
                kept = []
                for node in batch:
                    if not conflicts.missed(node):
                        kept.append(node)
                    elif not last:
                        following.append(tuple(node))
                batch = kept
            verdicts = simulate(batch)
            learn = _LEARN
            for i, node in enumerate(batch):
                verdict = None if verdicts is None else verdicts[i]
                if not verdict:
                    if conflicts.missed(node):  # ruled out by a conflict learned since it was made
                        if not last:
                            following.append(tuple(node))
                        continue
                    if verdict is not None and last:
                        if learn <= 0:
                            continue
                        learn -= 1
                    tick()
                    conflict = check(node)
                    if conflict is not None:
                        conflicts.add(conflict)
                        if not last:
                            following.append(tuple(node))
                        continue
                    if verdict is not None:
                        raise RuntimeError("simulation and SAT solver disagree on a candidate")
                known.add(node)
                record(node)

        seen: set[frozenset[int]] = set()
        pending: list[list[int]] = []
        known_conflicts = [len(conflicts.sets)]  # when the pending nodes were last filtered
        for parent in frontier:
            tick()
            missed = conflicts.missed(parent)
            spoiled = known.completing(parent)  # parent itself contains no known diagnosis
            for x in (conflicts.completions(missed) if last else conflicts.label(missed)):
                if x in spoiled:
                    continue
                node = frozenset((*parent, x))
                if node in seen:
                    continue
                seen.add(node)
                child = [*parent, x]
                if last or not conflicts.missed(child):
                    pending.append(child)
                else:
                    following.append(tuple(child))
            if len(pending) >= _BATCH:
                settle(pending)
                pending = []
                known_conflicts[0] = len(conflicts.sets)
        settle(pending)
        frontier = following
        yield d
