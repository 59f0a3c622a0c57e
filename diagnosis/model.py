"""A system model compiled to CNF: the one shape every loader (YAML, architecture, .bench) produces.

The diagnoser only needs clauses, the health variable of each candidate component, and the variable
of each observable proposition; building those is the loaders' job (``builder.ModelBuilder``).
"""
from __future__ import annotations

from collections.abc import Mapping
from types import CodeType

from agentspeak.errors import SourceError


class SystemModel:
    """Clauses over health variables AB(c) and observable propositions.

    ``components`` are the diagnosis candidates in declaration order (the output order of diagnoses);
    ``ab_var[c]`` is the variable that is true when c is abnormal; ``observables[name]`` is the variable
    of an observation; ``held`` are literals assumed on every query (assumptions that are not candidates).

    Weak-fault structure (netlists): ``readers[c]`` are the components reading c's output and ``output_of[c]``
    is c's output signal; the engine derives post-dominators from them (``dominators``): diagnoses that need no
    SAT check. Netlists also keep their ``gates``, (output, type, inputs) in topological order, and
    ``primary_inputs``, so that many candidates can be checked at once by simulation (``simulation``), and
    ``simulation``, those gates compiled for it once (``simulation.netlist_code``; None: compiled when used).

    Read-only by convention. A plain class rather than a frozen dataclass: ``dataclasses`` (with ``inspect``)
    is a sixth of a short ``faultmas diagnose`` (issue 23). ``fields()`` and ``SystemModel(*fields)`` are how
    ``netlist_cache`` keeps a model.
    """
    __slots__ = ("name", "source", "components", "ab_var", "observables", "clauses", "num_vars", "held", "kind",
                 "observable_kinds", "readers", "output_of", "gates", "primary_inputs", "simulation")

    def __init__(self, name: str, source: str, components: tuple[str, ...], ab_var: Mapping[str, int],
                 observables: Mapping[str, int], clauses: tuple[tuple[int, ...], ...], num_vars: int,
                 held: tuple[int, ...] = (), kind: str = "system", observable_kinds: Mapping[str, str] | None = None,
                 readers: Mapping[str, tuple[str, ...]] | None = None, output_of: Mapping[str, str] | None = None,
                 gates: tuple[tuple[str, str, tuple[str, ...]], ...] = (),
                 primary_inputs: tuple[str, ...] = (), simulation: CodeType | None = None) -> None:
        self.name = name
        self.source = source
        self.components = components
        self.ab_var = ab_var
        self.observables = observables
        self.clauses = clauses
        self.num_vars = num_vars
        self.held = held
        self.kind = kind
        self.observable_kinds = {} if observable_kinds is None else observable_kinds
        self.readers = {} if readers is None else readers
        self.output_of = {} if output_of is None else output_of
        self.gates = gates
        self.primary_inputs = primary_inputs
        self.simulation = simulation

    def fields(self) -> tuple:
        """The constructor's arguments, in order."""
        return tuple(getattr(self, f) for f in self.__slots__)

    def __eq__(self, other: object) -> bool:
        return type(other) is SystemModel and self.fields() == other.fields()

    __hash__ = None  # type: ignore[assignment]  # mutable mappings inside, as the dataclass had

    def __repr__(self) -> str:
        return f"SystemModel(name={self.name!r}, kind={self.kind!r}, {len(self.components)} components)"

    def observation_literals(self, observations: Mapping[str, bool]) -> list[int]:
        """Assumption literals for an observation set; unknown names raise ``UnknownObservation``."""
        out = []
        for name, value in observations.items():
            var = self.observables.get(name)
            if var is None:
                raise UnknownObservation(name, self)
            out.append(var if value else -var)
        return out


class UnknownObservation(SourceError, KeyError):
    """An observation the model does not declare (typo, or a model of another system)."""

    def __init__(self, name: str, model: SystemModel) -> None:
        known = ", ".join(sorted(model.observables)[:12])
        more = ", ..." if len(model.observables) > 12 else ""
        super().__init__(f"unknown observation {name!r} for model {model.name!r}; it declares: {known}{more}",
                         file=model.source)
        self.name = name

    def __str__(self) -> str:  # KeyError quotes its argument; keep the readable message
        return self.format()
