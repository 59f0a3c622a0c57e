"""``hz(topic)``: the message rate, from the filtered instantaneous rates 1/dt.

A rate cannot outlast silence: when no message came for as long as the filter's window should have
taken to refill (window_size periods of the filtered rate, at least 2; 10 for running filters), the
rate reported is 1/gap (a stopped publisher reads as a falling rate, then ~0 Hz). A mere slowdown is
left to the filter, so the verdict does not flap while the window catches up.
"""
from __future__ import annotations

from dataclasses import dataclass

from detection.message import Message
from detection.observers.base import Observer, Verdict


@dataclass
class HzObserver(Observer):
    kind = "hz"
    quantities = ("frequency",)
    _last_ns: int | None = None

    def on_message(self, msg: Message) -> None:
        if self._last_ns is not None and msg.t_ns > self._last_ns:
            self.filters["frequency"].add(1e9 / (msg.t_ns - self._last_ns))
        self._last_ns = msg.t_ns

    def evaluate(self, now_ns: int) -> Verdict | None:
        f = self.filters["frequency"]
        rate = f.value()
        if self._last_ns is not None and now_ns > self._last_ns:
            silent = (now_ns - self._last_ns) / 1e9
            if rate is None or silent > max(2, self.filter_spec.window_size or 10) / rate:
                return self._judge_rate(1.0 / silent)
        elif self._last_ns is None:
            return self._judge_rate(0.0)        # nothing since the start (evaluated after start_up_time)
        return self.judge()

    def _judge_rate(self, rate: float) -> Verdict:
        """Judge a rate seen in silence (the filter's window is stale) with the states' value tests."""
        for state in self.states:
            if all(t.value is None or t.value.accepts(rate) for _q, t in state.tests):
                return Verdict(state.healthy, rate, state.name)
        return Verdict(False, rate, None)
