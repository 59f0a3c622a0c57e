"""Incremental construction of a ``SystemModel``: variable numbering and clause collection."""
from __future__ import annotations

from diagnosis.model import SystemModel

TYPE_CHECKING = False     # typing.TYPE_CHECKING without importing typing (issue 23: start-up)
if TYPE_CHECKING:
    from types import CodeType

    from diagnosis.formula import Formula, Literal


class ModelBuilder:
    """Numbers health variables, propositions and auxiliaries, and collects clauses."""

    def __init__(self, name: str, source: str, kind: str) -> None:
        self.name = name
        self.source = source
        self.kind = kind
        self._ids: dict[tuple, int] = {}   # ("AB", c), ("atom", name), ("aux", n) -> its variable, from 1
        self.components: list[str] = []
        self.observables: dict[str, int] = {}
        self.observable_kinds: dict[str, str] = {}
        self.clauses: list[tuple[int, ...]] = []
        self.held: list[int] = []
        self.readers: dict[str, tuple[str, ...]] = {}
        self.output_of: dict[str, str] = {}
        self.gates: tuple[tuple[str, str, tuple[str, ...]], ...] = ()
        self.primary_inputs: tuple[str, ...] = ()
        self.simulation: CodeType | None = None

    @property
    def top(self) -> int:
        """The highest variable numbered so far."""
        return len(self._ids)

    def variable(self, key: tuple) -> int:
        """The variable of ``key`` (any hashable), numbered on first use."""
        var = self._ids.get(key)
        if var is None:
            var = self._ids[key] = len(self._ids) + 1
        return var

    def ab(self, component: str) -> int:
        return self.variable(("AB", component))

    def atom(self, name: str) -> int:
        return self.variable(("atom", name))

    def aux(self) -> int:
        return self.variable(("aux", len(self._ids) + 1))

    def var_of(self, literal: Literal) -> int:
        from diagnosis.formula import Ab

        return self.ab(literal.component) if isinstance(literal, Ab) else self.atom(literal.name)

    def add_component(self, name: str) -> None:
        self.components.append(name)
        self.ab(name)

    def add_observable(self, name: str, kind: str = "observation") -> int:
        var = self.atom(name)
        self.observables[name] = var
        self.observable_kinds[name] = kind
        return var

    def add_formula(self, formula: Formula) -> None:
        from diagnosis.formula import to_cnf

        self.clauses.extend(tuple(c) for c in to_cnf(formula, self.var_of, self.aux))

    def add_clause(self, clause: list[int] | tuple[int, ...]) -> None:
        self.clauses.append(tuple(clause))

    def build(self) -> SystemModel:
        return SystemModel(
            name=self.name, source=self.source, components=tuple(self.components),
            ab_var={c: self.ab(c) for c in self.components}, observables=dict(self.observables),
            clauses=tuple(self.clauses), num_vars=self.top, held=tuple(self.held), kind=self.kind,
            observable_kinds=dict(self.observable_kinds), readers=dict(self.readers),
            output_of=dict(self.output_of), gates=self.gates, primary_inputs=self.primary_inputs,
            simulation=self.simulation)


__all__ = ["ModelBuilder"]
