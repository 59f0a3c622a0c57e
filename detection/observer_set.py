"""Drives a set of observers from a stream of messages: dispatch by channel, evaluate on a fixed grid.

Evaluations happen at ``t0 + k / rate`` on the message clock. Before a message at time t is handed
over, every evaluation due at or before t runs; a live tap also calls ``advance(now)`` from a timer so
silence is noticed. Hence the same messages at the same times give the same observations, live or
replayed from a bag. An observation is emitted when it first becomes known and whenever it flips.
A message an observer cannot read is counted (``errors``) and logged, never fatal.
"""
from __future__ import annotations

import logging
from collections import Counter
from typing import Iterable, Sequence

from detection.message import Message, MessageError
from detection.observation import Observation
from detection.observers.base import Observer, Verdict

log = logging.getLogger("faultmas.detection")


class ObserverSet:
    def __init__(self, observers: Sequence[Observer], rate_hz: float = 10.0) -> None:
        if rate_hz <= 0:
            raise ValueError("the evaluation rate must be positive")
        self.observers = tuple(observers)
        self.period_ns = int(round(1e9 / rate_hz))
        self.by_channel: dict[str, list[Observer]] = {}
        for obs in self.observers:
            for ch in dict.fromkeys(obs.channels):
                self.by_channel.setdefault(ch, []).append(obs)
        self.t0_ns: int | None = None
        self._next_ns = 0
        self.verdicts: dict[str, tuple[Verdict | None, float]] = {}   # latest per observer, for status
        self.current: dict[str, Observation] = {}                    # last emitted per observation
        self.errors: Counter[str] = Counter()                        # unreadable messages per observer
        self.messages = 0

    @property
    def channels(self) -> tuple[str, ...]:
        return tuple(self.by_channel)

    def start(self, t0_ns: int) -> None:
        """Start the clock (the first message or tick starts it otherwise)."""
        self.t0_ns = t0_ns
        self._next_ns = t0_ns + self.period_ns
        for obs in self.observers:
            start = getattr(obs, "start", None)
            if start is not None:
                start(t0_ns)

    def feed(self, msg: Message) -> list[Observation]:
        """Run the evaluations due by ``msg.t_ns``, then hand the message to its observers."""
        out = self.advance(msg.t_ns)
        self.messages += 1
        for obs in self.by_channel.get(msg.channel, ()):
            try:
                obs.on_message(msg)
            except MessageError as exc:
                self.errors[obs.name] += 1
                n = self.errors[obs.name]
                if n == 1 or n % 1000 == 0:
                    log.warning("%s: unreadable message #%d dropped: %s", obs.name, n, exc)
        return out

    def feed_all(self, messages: Iterable[Message]) -> list[Observation]:
        out: list[Observation] = []
        for msg in messages:
            out.extend(self.feed(msg))
        return out

    def advance(self, now_ns: int) -> list[Observation]:
        """Run every evaluation due at or before ``now_ns``; the observations that changed."""
        if self.t0_ns is None:
            self.start(now_ns)
        out: list[Observation] = []
        while self._next_ns <= now_ns:
            out.extend(self.evaluate(self._next_ns))
            self._next_ns += self.period_ns
        return out

    def evaluate(self, t_ns: int) -> list[Observation]:
        out = []
        t = t_ns / 1e9
        for obs in self.observers:
            if t_ns - self.t0_ns < obs.start_up_time * 1e9:
                continue
            verdict = obs.evaluate(t_ns)
            self.verdicts[obs.name] = (verdict, t)
            if verdict is None:
                continue
            last = self.current.get(obs.name)
            if last is None or last.holds != verdict.holds:
                o = Observation(obs.name, verdict.holds, t, verdict.measured, verdict.state, obs.kind)
                self.current[obs.name] = o
                out.append(o)
        return out
