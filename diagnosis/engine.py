"""Consistency-based diagnosis (Reiter) on one persistent incremental SAT solver per model.

The model's clauses are loaded once. A query passes the observations, the held assumptions and a
cardinality bound as *assumptions*, so a new observation set rebuilds nothing. The bound comes from an
incremental totalizer over the health variables (``pysat.card.ITotalizer``): assuming ``-rhs[k]``
means "at most k components abnormal". Minimal diagnoses are enumerated level by level: at level k
every model found is a diagnosis of size exactly k that contains no smaller one (those are blocked),
hence subset-minimal; it is reported and its supersets blocked. Blocking clauses carry a per-query
activation literal, retired when the query ends, so they never leak into the next query.

Monotone models (no negative health literal in any clause: weak fault models such as netlists and
architecture models) never put the bound on the model's solver, which then only checks fixed
candidates ("exactly H faulty": propagation) and returns a conflict from its core when H fails:

* bounds up to ``_TREE_LIMIT`` (3, the usual case): a level-wise hitting-set tree over bit-set
  conflicts (``hs_tree``). On netlists whose inputs are all observed, candidates are checked in
  batches of thousands by bit-parallel simulation of the compiled netlist (``simulation``); the SAT
  solver is asked only for conflicts to branch on.
* larger bounds: a per-query hitting-set solver holds conflicts, blocking clauses and the bound
  (``hitting_sets``). Members lying in exactly the same conflicts are swapped into each diagnosis
  found (checked in one simulated batch on netlists), and on netlists every member may move up its
  post-dominator chain with no check at all (``dominators``); one clause blocks all those sets.
  Each set obtained is minimal when it contains no diagnosis found before, by the level argument.

Models with fault modes use the bound on the model's solver directly. The minimum cardinality comes
from RC2 (core-guided MaxSAT). Time limits interrupt the solver through one shared watchdog thread
(``deadline``). The totalizer and RC2 are imported when first needed, as are the hitting-set solver and the
post-dominators (bounds over 3): most queries use none of them, and a short ``faultmas diagnose`` is mostly
start-up (issue 23).

The default solver is Glucose 4 (python-sat's, made by ``diagnosis.sat`` without importing ``pysat.solvers``,
for start-up): it releases the GIL while solving (other threads of the agent keep
running) and honours ``interrupt()``, which the time limits rely on; CaDiCaL in python-sat does neither.
"""
from __future__ import annotations

import itertools
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence

from diagnosis.deadline import Deadline
from diagnosis.known import KnownDiagnoses
from diagnosis.hs_tree import tree_levels
from diagnosis.simulation import BatchSimulator, Compiled, netlist_code, simulation_function
from diagnosis.model import SystemModel
from diagnosis.sat import make_solver

TYPE_CHECKING = False     # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:
    from diagnosis.hitting_sets import HittingSetSolver

DEFAULT_SOLVER = "glucose4"
_RC2_SOLVER = {"glucose4": "g4", "glucose3": "g3", "minisat22": "m22", "cadical195": "cd19"}


class DiagnosisResult:
    """Minimal diagnoses (each a list of component names in model order), smallest first.

    ``min_cardinality`` is the size of the smallest diagnosis (None when there is none, or it was not
    reached in time); ``complete`` is True when every minimal diagnosis within the bound is listed;
    ``consistent_with_model`` is False when no set of faults explains the observations.
    (A plain class, not a dataclass: ``dataclasses`` is a sixth of a short ``faultmas diagnose``, issue 23.)
    """
    __slots__ = ("diagnoses", "min_cardinality", "complete", "seconds", "max_card", "consistent_with_model")

    def __init__(self, diagnoses: list[list[str]], min_cardinality: int | None, complete: bool, seconds: float,
                 max_card: int | None = None, consistent_with_model: bool = True) -> None:
        self.diagnoses = diagnoses
        self.min_cardinality = min_cardinality
        self.complete = complete
        self.seconds = seconds
        self.max_card = max_card
        self.consistent_with_model = consistent_with_model

    def __eq__(self, other: object) -> bool:
        return type(other) is DiagnosisResult and all(getattr(self, f) == getattr(other, f) for f in self.__slots__)

    def __repr__(self) -> str:
        return f"DiagnosisResult({', '.join(f'{f}={getattr(self, f)!r}' for f in self.__slots__)})"

    def to_json(self) -> dict:
        return {"diagnoses": self.diagnoses, "min_cardinality": self.min_cardinality,
                "complete": self.complete, "seconds": round(self.seconds, 6)}


_EAGER_BOUND = 4  # hitting-set totalizers are built for up to this many faults at once, then raised
_SWAP_LIMIT = 4  # levels up to which equivalent candidates are tried directly (subset test is 2^k)
_SPREAD_LIMIT = 200_000  # largest product of post-dominator chains expanded from one diagnosis
_BATCH = 1024  # variants simulated together
_TREE_LIMIT = 3  # size bounds up to which the hitting-set tree enumerates (``hs_tree``)
_STRUCTURE_CACHE = 8  # observed-signal sets whose post-dominators are kept per model


class _Structure:
    """Post-dominators of a netlist's gates for one set of observed signals, as health variables."""
    __slots__ = ("chains", "parent")

    def __init__(self, chains: dict[int, tuple[int, ...]], parent: dict[int, int]) -> None:
        self.chains = chains   # v -> v and its post-dominators, nearest first
        self.parent = parent   # v -> its immediate post-dominator


class TimedOut(Exception):
    """A SAT call hit the query's deadline."""


class _Query:
    """``with _Query(lock, deadline, solver):`` one query at a time on a solver; its deadline's timer ends with it.
    (A class, not ``contextlib.contextmanager``: importing contextlib was 2 % of a short ``faultmas diagnose``.)"""
    __slots__ = ("lock", "deadline", "solver")

    def __init__(self, lock: threading.Lock, deadline: Deadline, solver: object) -> None:
        self.lock, self.deadline, self.solver = lock, deadline, solver

    def __enter__(self) -> None:
        self.lock.acquire()

    def __exit__(self, *exc: object) -> None:
        try:
            self.deadline.release(self.solver)
        finally:
            self.lock.release()


def _collect(stream: Iterator[list[str]], max_count: int | None) -> tuple[list[list[str]], bool]:
    """Up to max_count answers of a stream, and whether the stream was exhausted (no limit hit)."""
    out: list[list[str]] = []
    try:
        for d in stream:
            if max_count is not None and len(out) >= max_count:
                return out, False
            out.append(d)
    except TimedOut:
        return out, False
    finally:
        stream.close()
    return out, True


class Diagnoser:
    """All queries for one model. Thread-safe: queries on one Diagnoser run one at a time."""

    def __init__(self, model: SystemModel, solver: str = DEFAULT_SOLVER) -> None:
        self.model = model
        self._lock = threading.Lock()
        self._solver = make_solver(solver, model.clauses)
        self._ab = [model.ab_var[c] for c in model.components]
        self._component_of = {v: c for c, v in model.ab_var.items()}
        self._index = {c: i for i, c in enumerate(model.components)}
        self._top = model.num_vars
        self._totalizer = None       # pysat.card.ITotalizer over the health variables, made when first bound
        self._solver_name = solver
        self._healthy = [-v for v in self._ab]
        self._position = {v: i for i, v in enumerate(self._ab)}
        self._gate_order: list[str] | None = None    # netlists: reverse topological, made when first needed
        self._structures: dict[frozenset[str], _Structure] = {}
        self._compiled: tuple[Compiled, dict[int, int], dict[str, int]] | None = None
        if model.gates:  # a netlist: compiled for batch simulation once (by its model), like the solver is loaded once
            code = model.simulation or netlist_code(model.gates, model.primary_inputs)
            self._compiled = (simulation_function(code),
                              {model.ab_var[g[0]]: i for i, g in enumerate(model.gates)},
                              {g[0]: i for i, g in enumerate(model.gates)})
        negative_ab = {-v for v in self._ab}
        self.monotone = negative_ab.isdisjoint(itertools.chain.from_iterable(model.clauses))
        try:  # prefer "healthy" so the solver's first guesses are small fault sets
            self._solver.set_phases([-v for v in self._ab])
        except NotImplementedError:
            pass

    def close(self) -> None:
        self._solver.delete()
        if self._totalizer is not None:
            self._totalizer.delete()

    # -- SAT plumbing -------------------------------------------------------------------------------

    def _fresh(self) -> int:
        self._top += 1
        return self._top

    def _at_most(self, k: int) -> list[int]:
        """Assumptions bounding the number of abnormal candidates to k (empty when k >= all)."""
        n = len(self._ab)
        if k >= n:
            return []
        if self._totalizer is None:
            from pysat.card import ITotalizer

            self._totalizer = ITotalizer(lits=self._ab, ubound=max(k, 1), top_id=self._top)
            self._solver.append_formula(self._totalizer.cnf.clauses)
            self._top = self._totalizer.top_id
        elif k > self._totalizer.ubound:
            self._totalizer.increase(ubound=k, top_id=self._top)
            if self._totalizer.nof_new:
                self._solver.append_formula(self._totalizer.cnf.clauses[-self._totalizer.nof_new:])
            self._top = self._totalizer.top_id
        return [-self._totalizer.rhs[k]]

    def _solve(self, assumptions: list[int], deadline: Deadline) -> bool:
        if deadline.end is None:
            return bool(self._solver.solve(assumptions=assumptions))
        if deadline.expired():
            raise TimedOut
        deadline.watch(self._solver)
        result = self._solver.solve_limited(assumptions=assumptions, expect_interrupt=True)
        if result is None:
            raise TimedOut
        return result

    def _query(self, deadline: Deadline) -> _Query:
        """One query at a time on this solver; its deadline's timer ends with it."""
        return _Query(self._lock, deadline, self._solver)

    def _abnormal(self) -> list[str]:
        model = self._solver.get_model()
        return [self._component_of[v] for v in self._ab if model[v - 1] > 0]

    def _base(self, observations: Mapping[str, bool]) -> list[int]:
        return [*self.model.held, *self.model.observation_literals(observations)]

    # -- queries ------------------------------------------------------------------------------------

    def is_consistent(self, observations: Mapping[str, bool], abnormal: Sequence[str] = ()) -> bool:
        """Is "exactly the components in ``abnormal`` are faulty" consistent with the observations?"""
        bad = {self.model.ab_var[c] for c in abnormal}
        with self._lock:
            return self._solve(self._base(observations) + [v if v in bad else -v for v in self._ab], Deadline(None))

    def minimal_diagnoses(self, observations: Mapping[str, bool], max_card: int | None = None,
                          deadline: Deadline | None = None) -> Iterator[list[str]]:
        """Stream the subset-minimal diagnoses of size <= max_card, smallest first, each level sorted.

        Raises TimedOut (after yielding what was found) when the deadline passes. Holds the model's
        lock while the generator is alive: exhaust or close it.
        """
        deadline = deadline or Deadline(None)
        limit = len(self._ab) if max_card is None else min(max_card, len(self._ab))
        with self._query(deadline):
            base = self._base(observations)
            if self.monotone and limit <= _TREE_LIMIT:  # its first check tells inconsistent observations
                yield from self._tree_levels(base, limit, deadline, self._simulator(observations))
                return
            if not self._solve(base, deadline):
                return  # nothing explains the observations, not even "everything is faulty"
            if self.monotone:
                yield from self._conflict_levels(base, limit, deadline, self._structure(observations),
                                                 self._simulator(observations))
                return
            act = self._fresh()
            try:
                for k in range(limit + 1):
                    level, timed_out = self._level(base + [act] + self._at_most(k), act, deadline)
                    yield from level
                    if timed_out:
                        raise TimedOut
            finally:
                self._solver.add_clause([-act])  # retire this query's blocking clauses

    def _check(self, base: list[int], deadline: Deadline) -> "Callable[[list[int]], list[int] | None]":
        """check(H): None if exactly H faulty is consistent, else a conflict from the solver's core
        (empty when the observations contradict the model whatever is faulty)."""
        template = base + self._healthy
        offset, position = len(base), self._position

        def check(candidate: list[int]) -> list[int] | None:
            assumptions = template.copy()
            for v in candidate:
                assumptions[offset + position[v]] = v
            if self._solve(assumptions, deadline):
                return None
            conflict = [-lit for lit in self._solver.get_core() or () if lit < 0 and -lit in position]
            return conflict  # empty: inconsistent whatever is faulty
        return check

    def _hitting_sets(self, levels: int) -> HittingSetSolver:
        from diagnosis.hitting_sets import HittingSetSolver

        return HittingSetSolver(self.model.num_vars + 1, self._solver_name, ubound=min(levels, _EAGER_BOUND))

    def _structure(self, observations: Mapping[str, bool]) -> _Structure | None:
        """Post-dominators for the signals observed (netlists only; None for other models)."""
        if not self.model.readers:
            return None
        from diagnosis.dominators import post_dominator_chains, reverse_topological

        if self._gate_order is None:
            self._gate_order = reverse_topological(self.model.readers)
        key = frozenset(observations)
        found = self._structures.get(key)
        if found is None:
            ab, output_of = self.model.ab_var, self.model.output_of
            observed = {g for g, signal in output_of.items() if signal in key}
            chains = post_dominator_chains(self._gate_order, self.model.readers, observed)
            found = _Structure({ab[g]: tuple(ab[x] for x in chain) for g, chain in chains.items()},
                               {ab[g]: ab[chain[1]] for g, chain in chains.items() if len(chain) > 1})
            if len(self._structures) >= _STRUCTURE_CACHE:
                self._structures.pop(next(iter(self._structures)))
            self._structures[key] = found
        return found

    def _spread(self, diagnosis: list[int], chains: Mapping[int, tuple[int, ...]],
                known: KnownDiagnoses, covered: set[frozenset[int]], deadline: Deadline) -> list[list[int]]:
        """The new minimal diagnoses made of a minimal one by moving members up their chains.

        Each such set is consistent (see ``dominators``) and has the diagnosis's size k; it is a new
        minimal diagnosis unless it contains one known (all smaller ones are, once lower levels are
        done). Prefixes that already contain a known diagnosis are cut off. ``covered`` holds the
        sets spread before: every set above one of them (member by member along the chains) was
        dealt with then, so the walk up a chain stops at the first covered completion."""
        pools = [chains.get(v, (v,)) for v in diagnosis]
        out: list[list[int]] = []
        chosen: list[int] = []

        def extend(i: int) -> None:
            if i == len(pools):
                out.append(list(chosen))
                return
            rest = diagnosis[i + 1:]
            for x in pools[i]:
                if x in chosen:
                    continue
                if frozenset((*chosen, x, *rest)) in covered:
                    break
                if known.within_adding(x, chosen):
                    continue
                chosen.append(x)
                extend(i + 1)
                chosen.pop()

        extend(0)
        covered.update(frozenset(d) for d in out)
        covered.add(frozenset(diagnosis))
        if deadline.expired():
            raise TimedOut
        return out

    def _simulator(self, observations: Mapping[str, bool]) -> "Callable[[], BatchSimulator | None]":
        """A netlist's batch simulator for these observations, built on first use (None if unusable)."""
        made: list[BatchSimulator | None] = []

        def get() -> BatchSimulator | None:
            if not made:
                sim = None
                if self._compiled is not None:
                    run, index, position = self._compiled
                    sim = BatchSimulator(run, position, self.model.primary_inputs, observations, index)
                made.append(sim if sim is not None and sim.usable else None)
            return made[0]
        return get

    def _tree_levels(self, base: list[int], limit: int, deadline: Deadline,
                     simulator: "Callable[[], BatchSimulator | None]") -> Iterator[list[str]]:
        """Small bounds on monotone models: the level-wise hitting-set tree (``hs_tree``)."""

        def simulate(nodes: list[list[int]]) -> list[bool] | None:
            sim = simulator()
            return None if sim is None else sim.consistent(nodes)

        def tick() -> None:
            if deadline.expired():
                raise TimedOut

        found: list[list[str]] = []
        levels = tree_levels(limit, self._check(base, deadline), simulate, KnownDiagnoses(),
                             lambda d: found.append(self._names(d)), tick)
        try:
            for _level in levels:
                done, found[:] = sorted(found, key=self._order), []
                yield from done
                if done and not done[0]:
                    return  # the empty diagnosis: nothing else is minimal
        except TimedOut:
            yield from sorted(found, key=self._order)
            raise
        finally:
            levels.close()

    def _conflict_levels(self, base: list[int], limit: int, deadline: Deadline,
                         structure: _Structure | None,
                         simulator: "Callable[[], BatchSimulator | None]") -> Iterator[list[str]]:
        import math    # here, as next_diagnosis: the tree (bounds up to 3) needs neither (start-up: issue 23)

        from diagnosis.hitting_sets import next_diagnosis

        hs = self._hitting_sets(limit)
        check = self._check(base, deadline)
        try:
            known = KnownDiagnoses()
            covered: set[frozenset[int]] = set()  # diagnoses spread along their chains
            for k in range(limit + 1):
                if deadline.expired():  # each level grows the bound's encoding: check before it
                    raise TimedOut
                if k > 0 and hs.candidate(len(hs.members)) is None:
                    # no set of any size hits every conflict without containing a diagnosis found:
                    # no level above has anything (a 6,000-gate chain went on raising the bound to
                    # thousands, 49 s and 3.3 GB, to find nothing)
                    return
                found: list[list[str]] = []

                def record(diagnosis: list[int]) -> None:
                    """Keep a new minimal diagnosis. On a netlist also every set its members'
                    post-dominators make of it (no SAT call), and block them all in one clause."""
                    if structure is not None and math.prod(
                            len(structure.chains.get(v, ())) or 1 for v in diagnosis) <= _SPREAD_LIMIT:
                        new = self._spread(diagnosis, structure.chains, known, covered, deadline)
                        hs.block_up(diagnosis, structure.parent)
                    else:
                        new = [diagnosis]
                        hs.block(diagnosis)
                    for d in new:
                        known.add(d)
                        found.append(self._names(d))

                def try_variants(variants: list[list[int]]) -> None:
                    """Variants hit the same conflicts as a diagnosis, so most are diagnoses too:
                    a netlist simulates them all at once; the SAT solver checks the rest (and the
                    failures, for their conflicts)."""
                    sim = simulator()
                    verdicts = (sim.consistent(variants)
                                if sim is not None else [None] * len(variants))
                    learned: list[set[int]] = []  # conflicts found while trying the variants
                    for variant, verdict in zip(variants, verdicts):
                        if deadline.expired():
                            raise TimedOut
                        if known.within(variant) or any(c.isdisjoint(variant) for c in learned):
                            continue
                        conflict = None if verdict else check(variant)
                        if conflict is None:
                            record(variant)
                        else:
                            hs.add_conflict(conflict)
                            learned.append(set(conflict))

                try:
                    while (candidate := next_diagnosis(hs, k, check)) is not None:
                        record(candidate)
                        if k > _SWAP_LIMIT:
                            continue
                        variants: list[list[int]] = []
                        for combo in hs.equivalents(candidate):  # no hitting-set search for these
                            variant = sorted(combo)
                            if not known.within(variant):
                                variants.append(variant)
                            if len(variants) >= _BATCH:
                                try_variants(variants)
                                variants = []
                        try_variants(variants)
                except TimedOut:
                    yield from sorted(found, key=self._order)
                    raise
                yield from sorted(found, key=self._order)
                if found and not found[0]:
                    return  # the empty diagnosis: nothing else is minimal
        finally:
            hs.close()

    def _level(self, assumptions: list[int], act: int, deadline: Deadline) -> tuple[list[list[str]], bool]:
        """The diagnoses of one level, sorted, and whether the deadline cut the level short."""
        found: list[list[str]] = []
        timed_out = False
        try:
            while self._solve(assumptions, deadline):
                diagnosis = self._abnormal()
                found.append(diagnosis)
                self._solver.add_clause([-act, *(-self.model.ab_var[c] for c in diagnosis)])
        except TimedOut:
            timed_out = True
        return sorted(found, key=self._order), timed_out

    def _names(self, ab_vars: list[int]) -> list[str]:
        """Component names of health variables, in model order."""
        return sorted((self._component_of[v] for v in ab_vars), key=self._index.__getitem__)

    def _order(self, diagnosis: list[str]) -> list[int]:
        return [self._index[c] for c in diagnosis]

    def minimum_cardinality(self, observations: Mapping[str, bool], deadline: Deadline | None = None,
                            ) -> tuple[int | None, list[str] | None]:
        """Smallest number of faults that explains the observations, with one such diagnosis.

        RC2 (core-guided MaxSAT: hard = model and observations, soft = each component healthy) on a
        solver of its own for this query; its oracle calls are interrupted when the deadline passes
        (RC2's own ``interrupt`` lets it go on processing cores for seconds on c6288).
        None, None when nothing explains the observations.
        """
        deadline = deadline or Deadline(None)
        if deadline.expired():
            raise TimedOut
        from pysat.examples.rc2 import RC2
        from pysat.formula import WCNF

        wcnf = WCNF()
        wcnf.extend([list(c) for c in self.model.clauses])
        wcnf.extend([[lit] for lit in self._base(observations)])
        for v in self._ab:
            wcnf.append([-v], weight=1)
        with RC2(wcnf, solver=_RC2_SOLVER.get(self._solver_name, "g4")) as rc2:
            oracle = rc2.oracle
            if deadline.end is not None:  # every oracle call of RC2 stops at the deadline
                call = oracle.solve_limited

                def limited(assumptions: Sequence[int] = (), expect_interrupt: bool = False) -> bool:
                    result = None if deadline.expired() else call(assumptions=assumptions, expect_interrupt=True)
                    if result is None:
                        raise TimedOut
                    return result
                oracle.solve_limited = limited
                deadline.watch(oracle)
            try:
                model = rc2.compute()
            finally:
                deadline.release(oracle)
        if model is None:
            return None, None
        true = {lit for lit in model if lit > 0}
        best = [self._component_of[v] for v in self._ab if v in true]
        return len(best), best

    def diagnose(self, observations: Mapping[str, bool], max_card: int | None = None,
                 max_count: int | None = None, timeout: float | None = None,
                 min_card_only: bool = False) -> DiagnosisResult:
        """All minimal diagnoses up to ``max_card`` (or only minimum-cardinality ones), with limits."""
        started = time.perf_counter()
        deadline = Deadline(timeout)
        if min_card_only:
            return self._diagnose_min_card(observations, max_count, deadline, started)
        diagnoses, complete = _collect(self.minimal_diagnoses(observations, max_card, deadline), max_count)
        # levels run in order and each is exhausted before the next: the first answer has minimum size
        min_card = len(diagnoses[0]) if diagnoses else None
        consistent = bool(diagnoses) or not complete or self._explainable(observations)
        return DiagnosisResult(diagnoses, min_card, complete, time.perf_counter() - started, max_card, consistent)

    def _diagnose_min_card(self, observations: Mapping[str, bool], max_count: int | None,
                           deadline: Deadline, started: float) -> DiagnosisResult:
        try:
            k, _one = self.minimum_cardinality(observations, deadline)
        except TimedOut:
            return DiagnosisResult([], None, False, time.perf_counter() - started)
        if k is None:
            return DiagnosisResult([], None, True, time.perf_counter() - started, consistent_with_model=False)
        # every diagnosis of minimum size is subset-minimal: enumerate just that level
        with self._query(deadline):
            diagnoses, complete = _collect(self._one_level(self._base(observations), k, deadline), max_count)
        diagnoses.sort(key=self._order)
        return DiagnosisResult(diagnoses, k, complete, time.perf_counter() - started, k)

    def _one_level(self, base: list[int], k: int, deadline: Deadline) -> Iterator[list[str]]:
        """Every diagnosis of size <= k, when k is the minimum cardinality (so all are minimal)."""
        from diagnosis.hitting_sets import next_diagnosis

        if self.monotone:
            hs = self._hitting_sets(k)
            check = self._check(base, deadline)
            try:
                while (candidate := next_diagnosis(hs, k, check)) is not None:
                    hs.block(candidate)
                    yield self._names(candidate)
            finally:
                hs.close()
            return
        act = self._fresh()
        assumptions = base + [act] + self._at_most(k)
        try:
            while self._solve(assumptions, deadline):
                d = self._abnormal()
                self._solver.add_clause([-act, *(-self.model.ab_var[c] for c in d)])
                yield d
        finally:
            self._solver.add_clause([-act])

    def _explainable(self, observations: Mapping[str, bool]) -> bool:
        with self._lock:
            return self._solve(self._base(observations), Deadline(None))

    def possibly_faulty(self, observations: Mapping[str, bool], components: Sequence[str] | None = None,
                        timeout: float | None = None) -> list[str]:
        """PosAb: the components that are faulty in some minimum-cardinality diagnosis.

        No enumeration: for each component c not yet seen in a diagnosis, one search for "AB(c) and
        at most k faults" (k the minimum cardinality): a SAT call on the model's solver, or on the
        conflict route a hitting-set search whose conflicts carry over from one component to the next.
        Every diagnosis found on the way marks all its members. With k minimal every such diagnosis is
        subset-minimal, so the answer is exact. Empty when no fault is needed or nothing explains them.
        """
        deadline = Deadline(timeout)
        k, first = self.minimum_cardinality(observations, deadline)
        if not k:
            return []
        asked = list(self.model.components if components is None else components)
        for c in asked:
            if c not in self.model.ab_var:
                raise KeyError(f"unknown component {c!r} in model {self.model.name!r}")
        known = set(first or ())
        from diagnosis.hitting_sets import next_diagnosis

        with self._query(deadline):
            base = self._base(observations)
            if self.monotone:
                hs = self._hitting_sets(k)
                check = self._check(base, deadline)
                try:
                    for c in asked:
                        if c not in known:
                            found = next_diagnosis(hs, k, check, extra=[self.model.ab_var[c]])
                            known.update(self._names(found or []))
                finally:
                    hs.close()
            else:
                bounded = base + self._at_most(k)
                for c in asked:
                    if c not in known and self._solve(bounded + [self.model.ab_var[c]], deadline):
                        known.update(self._abnormal())
        return [c for c in asked if c in known]
