"""faultmas: detection — what finds faults in a running system by watching it from outside.

Observers (the TU Graz kinds: activated, resource, timeout, hz, timestamp, timing, score, movement)
read messages through taps (rclpy, Zenoh, bag replay) and emit ``Observation`` s; the ``Pipeline``
hands them to the diagnoser (``diagnosis/``) and the rule engine. The learned detector lives in
``detection.learned`` beside them and emits into the same pipeline. This package never imports
``agents/``. The format and the API: docs/observers.md.
"""
from __future__ import annotations

from typing import Any

__all__ = ["Observation", "Message", "Observer", "ObserverSet", "Pipeline", "Update", "load_observers"]

_WHERE = {"Observation": "detection.observation", "Message": "detection.message",
          "Observer": "detection.observers.base", "ObserverSet": "detection.observer_set",
          "Pipeline": "detection.pipeline", "Update": "detection.pipeline",
          "load_observers": "detection.config"}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        import importlib
        return getattr(importlib.import_module(_WHERE[name]), name)
    raise AttributeError(f"module 'detection' has no attribute {name!r}")
