"""A system model compiled to CNF: the one shape every loader (YAML, architecture, .bench) produces.

The diagnoser only needs clauses, the health variable of each candidate component, and the variable
of each observable proposition; building those is the loaders' job (``builder.ModelBuilder``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

from agentspeak.errors import SourceError


@dataclass(frozen=True)
class SystemModel:
    """Clauses over health variables AB(c) and observable propositions.

    ``components`` are the diagnosis candidates in declaration order (the output order of diagnoses);
    ``ab_var[c]`` is the variable that is true when c is abnormal; ``observables[name]`` is the variable
    of an observation; ``held`` are literals assumed on every query (assumptions that are not candidates).
    """
    name: str
    source: str
    components: tuple[str, ...]
    ab_var: Mapping[str, int]
    observables: Mapping[str, int]
    clauses: tuple[tuple[int, ...], ...]
    num_vars: int
    held: tuple[int, ...] = ()
    kind: str = "system"
    observable_kinds: Mapping[str, str] = field(default_factory=dict)
    # weak-fault structure (netlists): the components reading c's output, and c's output signal.
    # The engine derives post-dominators from them (``dominators``): diagnoses that need no SAT check.
    readers: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    output_of: Mapping[str, str] = field(default_factory=dict)
    # netlists also keep their gates, (output, type, inputs) in topological order, and primary inputs,
    # so that many candidates can be checked at once by simulation (``simulation``)
    gates: tuple[tuple[str, str, tuple[str, ...]], ...] = ()
    primary_inputs: tuple[str, ...] = ()

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
