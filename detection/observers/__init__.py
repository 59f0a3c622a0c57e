"""The eight observer kinds of the paper, by the name a configuration uses."""
from __future__ import annotations

from detection.observers.activated import ActivatedObserver
from detection.observers.base import Observer, State, Verdict
from detection.observers.hz import HzObserver
from detection.observers.movement import MovementObserver
from detection.observers.resource import ResourceObserver
from detection.observers.score import ScoreObserver
from detection.observers.timeout import TimeoutObserver
from detection.observers.timestamp import TimestampObserver
from detection.observers.timing import TimingObserver

KINDS: dict[str, type[Observer]] = {cls.kind: cls for cls in (
    ActivatedObserver, ResourceObserver, TimeoutObserver, HzObserver, TimestampObserver, TimingObserver,
    ScoreObserver, MovementObserver)}

__all__ = ["KINDS", "Observer", "State", "Verdict"]
