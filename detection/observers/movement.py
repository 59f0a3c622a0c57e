"""``movement(a, b)``: two motion sources agree (e.g. IMU yaw rate vs wheel-odometry yaw rate).

Each source's value (a velocity field) is differentiated to an acceleration (``differentiate: false``
compares the values themselves); the residual ``a - b`` is sampled at every message of source A once
both sources have one. Healthy, the residual is ~N(0, s): test it with ``student_t`` (true_mean 0) or a
nominal test on its filtered value.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from detection.message import Message
from detection.observers.base import Observer


@dataclass
class MovementObserver(Observer):
    kind = "movement"
    quantities = ("residual",)
    paths: tuple[tuple[str, ...], tuple[str, ...]] = (("data",), ("data",))
    differentiate: bool = True
    _last: list = field(default_factory=lambda: [None, None])      # per source: (t_ns, value)
    _signal: list = field(default_factory=lambda: [None, None])    # per source: value or its derivative

    def on_message(self, msg: Message) -> None:
        updated_a = False
        for i in (0, 1):
            if msg.channel != self.channels[i]:
                continue
            value = msg.field(self.paths[i])
            last = self._last[i]
            self._last[i] = (msg.t_ns, value)
            if not self.differentiate:
                self._signal[i] = value
            elif last is not None and msg.t_ns > last[0]:
                self._signal[i] = (value - last[1]) * 1e9 / (msg.t_ns - last[0])
            else:
                continue
            updated_a = updated_a or i == 0
        if updated_a and self._signal[1] is not None:
            self.filters["residual"].add(self._signal[0] - self._signal[1])
