"""Level-wise minimal diagnoses for monotone models, by conflicts and hitting sets.

A model is *monotone* when no clause contains a negative health literal (weak fault models: ISCAS
netlists, the paper's architecture models): declaring one more component faulty never makes a
consistent set inconsistent. Then Reiter's duality holds with cheap pieces:

* the model's persistent solver only ever answers "is exactly H faulty consistent?" (all health
  literals fixed by assumptions: pure propagation, no search) and, when not, its core is a conflict;
* a small per-query *hitting-set solver* holds the conflicts, the blocking clauses of diagnoses found
  and a totalizer over only the components that occur in conflicts; assuming "at most k" bounds it.

At level k a consistent candidate is a minimal diagnosis of size k, for the reason given in
``engine``'s module doc. Keeping the totalizer out of the model's solver is what makes this fast: a
check on a 3,500-gate circuit costs under a millisecond instead of about two.
"""
from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator, Mapping, Sequence

from diagnosis.sat import make_solver


class HittingSetSolver:
    """Candidates that hit every conflict seen so far and contain no blocked set."""

    def __init__(self, first_free_var: int, solver: str, ubound: int = 1) -> None:
        self.solver = make_solver(solver)
        self.top = first_free_var - 1
        # the totalizer counts up to ubound; raised when a higher level asks. Its size grows with the
        # bound, but one built for the final small bound searches much faster than one raised to it.
        self.ubound = max(ubound, 1)
        self.members: list[int] = []       # health variables that occur in some conflict
        self._member_set: set[int] = set()
        self.totalizer = None     # pysat.card.ITotalizer, imported when first needed (start-up: issue 23)
        self._signature: dict[int, int] = {}            # member -> bit set of the conflicts it is in
        self._classes: dict[int, list[int]] = {}        # bit set -> members with exactly that set
        self._conflicts = 0
        self._up: dict[int, int] = {}                   # member -> "it or an ancestor chosen" variable

    def close(self) -> None:
        self.solver.delete()
        if self.totalizer is not None:
            self.totalizer.delete()

    def add_conflict(self, ab_vars: Sequence[int]) -> None:
        self.solver.add_clause(list(ab_vars))
        self._add_members(ab_vars)
        bit = 1 << self._conflicts
        self._conflicts += 1
        for v in ab_vars:
            old = self._signature[v]
            self._classes[old].remove(v)
            self._signature[v] = old | bit
            self._classes.setdefault(old | bit, []).append(v)

    def equivalents(self, candidate: Sequence[int]) -> Iterator[tuple[int, ...]]:
        """Sets that hit the same conflicts as ``candidate``: each member swapped for one that is in
        exactly the same conflicts (gates along one path often are). Yielded aligned with the
        candidate (position i replaces candidate[i]); the candidate itself is skipped."""
        pools = [list(self._classes[self._signature[v]]) for v in candidate]
        seen = {frozenset(candidate)}
        for combo in itertools.product(*pools):
            variant = frozenset(combo)
            if len(variant) == len(combo) and variant not in seen:
                seen.add(variant)
                yield combo

    def _add_members(self, ab_vars: Sequence[int]) -> None:
        """Count these components in the bound and report them in candidates from now on."""
        new = [v for v in ab_vars if v not in self._member_set]
        if not new:
            return
        self.members.extend(new)
        self._member_set.update(new)
        for v in new:
            self._signature[v] = 0
            self._classes.setdefault(0, []).append(v)
        self.solver.set_phases([-v for v in new])
        if self.totalizer is None:
            from pysat.card import ITotalizer

            self.totalizer = ITotalizer(lits=list(new), ubound=self.ubound, top_id=self.top)
            self.solver.append_formula(self.totalizer.cnf.clauses)
        else:
            self.totalizer.extend(lits=list(new), ubound=self.ubound, top_id=self.top)
            if self.totalizer.nof_new:
                self.solver.append_formula(self.totalizer.cnf.clauses[-self.totalizer.nof_new:])
        self.top = self.totalizer.top_id

    def block(self, ab_vars: Sequence[int]) -> None:
        """No candidate may contain all of these (a diagnosis found: its supersets are not minimal)."""
        self.solver.add_clause([-v for v in ab_vars])

    def block_up(self, ab_vars: Sequence[int], parent: Mapping[int, int]) -> None:
        """No candidate may take, for every member v, v or one of its ancestors in ``parent`` (a forest).

        One clause over one "v or an ancestor is chosen" variable per member; those variables are
        shared by all such clauses of this solver, so the tree costs two clauses per node at most."""
        self.solver.add_clause([-self._up_var(v, parent) for v in ab_vars])

    def _up_var(self, v: int, parent: Mapping[int, int]) -> int:
        path = []
        while v not in self._up and v is not None:
            path.append(v)
            v = parent.get(v)
        above = self._up.get(v) if v is not None else None
        for node in reversed(path):  # from the top down: y_node <- node, y_node <- y_parent
            self.top += 1
            y = self._up[node] = self.top
            self.solver.add_clause([-node, y])
            if above is not None:
                self.solver.add_clause([-above, y])
            above = y
        return above

    def candidate(self, k: int, extra: Sequence[int] = ()) -> list[int] | None:
        """A hitting set of at most k members (plus ``extra`` assumptions), or None when there is none."""
        self._add_members([lit for lit in extra if lit > 0])  # a component assumed faulty counts too
        assumptions = list(extra)
        if self.totalizer is not None and k < len(self.members):
            if k > self.ubound:
                self.ubound = k
                self.totalizer.increase(ubound=k, top_id=self.top)
                if self.totalizer.nof_new:
                    self.solver.append_formula(self.totalizer.cnf.clauses[-self.totalizer.nof_new:])
                self.top = self.totalizer.top_id
            assumptions.append(-self.totalizer.rhs[k])
        if not self.solver.solve(assumptions=assumptions):
            return None
        model = self.solver.get_model() or []
        return [v for v in self.members if model[v - 1] > 0] if self.members else []


def next_diagnosis(hs: HittingSetSolver, k: int, check: Callable[[list[int]], list[int] | None],
                   extra: Sequence[int] = ()) -> list[int] | None:
    """The next consistent hitting set of size <= k, learning conflicts on the way; None if none is left.

    ``check(H)`` returns None when "exactly H faulty" is consistent, else a conflict (health
    variables of components that cannot all be healthy), never empty.
    """
    while True:
        candidate = hs.candidate(k, extra)
        if candidate is None:
            return None
        conflict = check(candidate)
        if conflict is None:
            return candidate
        hs.add_conflict(conflict)
