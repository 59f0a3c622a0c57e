"""The observer interface: fed messages one at a time, judged a few times per second.

``on_message`` is called for every message on one of the observer's ``channels`` and only stores
(filters' ``add``); ``evaluate(now_ns)`` decides the verdict from what was stored. Nothing here reads
a clock or does I/O: a tap, a bag replay or a simulator drives the observer (``ObserverSet``), so the
same messages at the same times always give the same observations.

A verdict comes from the observer's ``states`` (tug_observers' layout): the first state whose tests all
pass decides; a state is healthy unless configured ``healthy: false`` (a known faulty mode, named in the
output). No state passing means the observation does not hold.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, NamedTuple

from detection.filters import Filter, FilterSpec
from detection.message import Message
from detection.state_tests import QuantityTest


@dataclass(frozen=True)
class State:
    name: str
    tests: tuple[tuple[str, QuantityTest], ...]   # (quantity, test), all must pass
    number: int | None = None
    healthy: bool = True


class Verdict(NamedTuple):
    holds: bool
    measured: float | None = None
    state: str | None = None


@dataclass
class Observer:
    """Base of every kind. ``name`` is the observation it emits (``hz(scan)``)."""
    kind: ClassVar[str] = ""
    quantities: ClassVar[tuple[str, ...]] = ()     # what its states may test, first one reported

    name: str
    channels: tuple[str, ...]
    states: tuple[State, ...] = ()
    filter_spec: FilterSpec = field(default_factory=FilterSpec)
    start_up_time: float = 0.0
    filters: dict[str, Filter] = field(init=False)

    def __post_init__(self) -> None:
        self.filters = {q: self.filter_spec.make() for q in self.quantities}

    def on_message(self, msg: Message) -> None:
        """Store what the message says (raise ``MessageError`` if it cannot be read)."""
        raise NotImplementedError

    def evaluate(self, now_ns: int) -> Verdict | None:
        """The verdict at ``now_ns``; None while unknown (not enough data yet)."""
        return self.judge()

    def judge(self) -> Verdict | None:
        """The first state whose tests pass; unknown while a test lacks data and none passed."""
        unknown = False
        primary = self.quantities[0] if self.quantities else None
        for state in self.states:
            measured = None
            passed = True
            for quantity, test in state.tests:
                result = test.check(self.filters[quantity])
                if result is None:
                    unknown, passed = True, False
                    break
                ok, value = result
                if quantity == primary or measured is None:
                    measured = value
                if not ok:
                    passed = False
                    break
            if passed:
                return Verdict(state.healthy, measured, state.name)
        if unknown:
            return None
        value = self.filters[primary].value() if primary else None
        return None if value is None and primary else Verdict(False, value, None)
