"""What ``faultmas observe`` shows: a status table refreshed in place on a terminal, else one line (or
one JSON object) per change."""
from __future__ import annotations

import json
import time
from typing import TextIO

from detection.observer_set import ObserverSet
from detection.pipeline import Update

UNITS = {"hz": "Hz", "timeout": "s", "timestamp": "s", "timing": "s", "resource": "% cpu"}


def _clock(t: float) -> str:
    return time.strftime("%H:%M:%S", time.localtime(t)) + f".{int(t * 1000) % 1000:03d}"


def _diagnoses(update: Update) -> str:
    if update.diagnoses is None:
        return "-"
    if update.diagnoses == ((),):
        return "no fault"
    if not update.diagnoses:
        return "none explains it"
    return " ".join("{" + ", ".join(d) + "}" for d in update.diagnoses)


def change_line(update: Update) -> str:
    """``12:00:01.300 ~hz(scan)=2.95 Hz | diagnoses {laser_driver} | fired slow_laser``."""
    parts = []
    for o in update.changed:
        value = "" if o.measured is None else f"={o.measured:.4g}"
        unit = UNITS.get(o.source, "")
        parts.append(f"{o.literal}{value}{' ' + unit if value and unit else ''}")
    line = f"{_clock(update.time)} {', '.join(parts)} | diagnoses {_diagnoses(update)}"
    if update.fired:
        line += " | fired " + ", ".join(f.rule.name + (f" (failed: {f.error})" if f.error else "")
                                        for f in update.fired)
    return line


def json_line(update: Update) -> str:
    return json.dumps(update.to_json())


class StatusTable:
    """The whole state, redrawn in place (ANSI home + clear) at most a few times per second."""

    def __init__(self, observers: ObserverSet, out: TextIO) -> None:
        self.observers = observers
        self.out = out
        self.fired: list[str] = []
        self.last: Update | None = None

    def record(self, update: Update) -> None:
        self.last = update
        for f in update.fired:
            self.fired.append(f"{_clock(update.time)} {f.rule.name}" + (f" (failed: {f.error})" if f.error else ""))
        del self.fired[:-8]

    def render(self) -> str:
        rows = [f"{'observer':34} {'state':12} {'value':>12}  verdict"]
        for obs in self.observers.observers:
            verdict, _t = self.observers.verdicts.get(obs.name, (None, None))
            errors = self.observers.errors.get(obs.name, 0)
            if verdict is None:
                value, state, text = "", "", "unknown"
            else:
                unit = UNITS.get(obs.kind, "")
                value = "" if verdict.measured is None else f"{verdict.measured:.4g} {unit}".strip()
                state, text = verdict.state or "-", "ok" if verdict.holds else "FAULT"
            rows.append(f"{obs.name:34} {state:12} {value:>12}  {text}"
                        + (f"  ({errors} unreadable)" if errors else ""))
        names = {obs.name for obs in self.observers.observers}
        for o in sorted((self.last.observations.values() if self.last else ()), key=lambda o: o.name):
            if o.name not in names:          # another detector's (the learned resource observer's)
                value = "" if o.measured is None else f"{o.measured:.4g}"
                rows.append(f"{o.name:34} {o.source or '-':12} {value:>12}  {'ok' if o.holds else 'FAULT'}")
        rows.append("")
        rows.append("diagnoses: " + (_diagnoses(self.last) if self.last else "-"))
        rows.append("rules fired: " + ("; ".join(self.fired) if self.fired else "none"))
        return "\n".join(rows)

    def draw(self) -> None:
        self.out.write("\x1b[H\x1b[2J" + self.render() + "\n")
        self.out.flush()
