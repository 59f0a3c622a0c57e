"""Obs -> diagnoser -> rule engine -> listeners: what happens to observations once emitted.

``Pipeline.observe`` takes the observations that changed (from an ``ObserverSet``, the learned detector
or a simulator), updates Obs, recomputes the diagnoses and PosAb with the architecture model only when
Obs changed (never per message), runs the rules (``diagnosis.rules``, the paper's semantics by default)
and hands one ``Update`` to every listener (status table, ``/observers/info``, agents' percepts).
Thread-safe: producers on several threads may call ``observe``.
"""
from __future__ import annotations

import logging
import threading
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Mapping, Sequence

from detection.observation import Observation
from diagnosis.actions import ActionEnvironment
from diagnosis.model import SystemModel
from diagnosis.rules import Firing, Rule, RuleEngine

log = logging.getLogger("faultmas.detection")


@dataclass(frozen=True)
class Update:
    """One change: what changed, the resulting Obs, diagnoses, PosAb and the rules that fired."""
    time: float
    changed: tuple[Observation, ...]
    observations: Mapping[str, Observation]
    diagnoses: tuple[tuple[str, ...], ...] | None = None      # None: no model
    possibly_faulty: frozenset[str] | None = None               # PosAb; None: no model
    fired: tuple[Firing, ...] = ()
    seconds: float = 0.0                                        # diagnosis time

    @property
    def obs(self) -> dict[str, bool]:
        """Obs as name -> holds."""
        return {name: o.holds for name, o in self.observations.items()}

    def to_json(self) -> dict[str, Any]:
        return {"time": self.time, "changed": [o.to_json() for o in self.changed],
                "obs": sorted(o.literal for o in self.observations.values()),
                "diagnoses": None if self.diagnoses is None else [list(d) for d in self.diagnoses],
                "possibly_faulty": None if self.possibly_faulty is None else sorted(self.possibly_faulty),
                "fired": [{"rule": f.rule.name, "error": f.error} for f in self.fired]}


Listener = Callable[[Update], None]


@dataclass
class Pipeline:
    model: SystemModel | None = None
    rules: Sequence[Rule] = ()
    environment: ActionEnvironment | None = None
    max_card: int | None = None
    diagnosis_timeout: float | None = 5.0
    listeners: list[Listener] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.observations: dict[str, Observation] = {}
        self.last: Update | None = None
        self._engine = RuleEngine(self.rules, self.environment)
        self._diagnoser = None
        self._lock = threading.RLock()
        self._ignored: set[str] = set()
        if self.model is not None:
            from diagnosis.engine import Diagnoser   # python-sat loads only when a model is used
            self._diagnoser = Diagnoser(self.model)

    def add_listener(self, listener: Listener) -> None:
        self.listeners.append(listener)

    def observe(self, observations: Iterable[Observation]) -> Update | None:
        """Take new observations; an ``Update`` when Obs changed, else None."""
        with self._lock:
            changed = []
            for o in observations:
                last = self.observations.get(o.name)
                self.observations[o.name] = o
                if last is None or last.holds != o.holds:
                    changed.append(o)
            if not changed:
                return None
            update = self._update(tuple(changed))
            self.last = update
        for listener in list(self.listeners):
            try:
                listener(update)
            except Exception:          # a broken listener must not stop the others or the observers
                log.exception("observer listener %r failed", listener)
        return update

    def _update(self, changed: tuple[Observation, ...]) -> Update:
        obs = {name: o.holds for name, o in self.observations.items()}
        diagnoses = posab = None
        seconds = 0.0
        if self._diagnoser is not None:
            known = {n: v for n, v in obs.items() if n in self.model.observables}
            for name in obs.keys() - known.keys() - self._ignored:
                self._ignored.add(name)
                log.warning("observation %s is not declared by model %s: not diagnosed", name, self.model.name)
            result = self._diagnoser.diagnose(known, max_card=self.max_card, timeout=self.diagnosis_timeout)
            diagnoses = tuple(tuple(d) for d in result.diagnoses)
            posab = frozenset(c for d in diagnoses if len(d) == (result.min_cardinality or 0) for c in d)
            seconds = result.seconds
        fired = tuple(self._engine.update(obs, posab))
        return Update(changed[-1].time, changed, dict(self.observations), diagnoses, posab, fired, seconds)

    def close(self) -> None:
        if self._diagnoser is not None:
            self._diagnoser.close()
            self._diagnoser = None
