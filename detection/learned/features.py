"""The paper's features at each 1 Hz tick, per channel: for windows of 2.5 s and 6 s the element-wise
mean of the encoded events and their count, plus the last event.

One function, :func:`window_features`, computes them for any number of ticks from a channel's event
arrays: offline over a whole recorded run, online over the last 6 s buffered by
:class:`ChannelBuffer`, so both give the same numbers.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

WINDOWS_S: tuple[float, ...] = (2.5, 6.0)
TICK_S = 1.0


def feature_names(channel: str, columns: Sequence[str]) -> list[str]:
    """Names of :func:`window_features`' columns for ``channel`` with event ``columns``."""
    names = []
    for w in WINDOWS_S:
        names += [f"{channel}|mean{w:g}s|{c}" for c in columns] + [f"{channel}|count{w:g}s"]
    return names + [f"{channel}|last|{c}" for c in columns]


def window_features(times: np.ndarray, values: np.ndarray, ticks: np.ndarray) -> np.ndarray:
    """``(len(ticks), 2·(d+1) + d)`` features from events at sorted ``times`` with ``values`` (n × d).

    Window ``w`` at tick ``t`` holds the events with ``t - w < time ≤ t``; no event: mean 0, count 0;
    the last event is the latest at or before ``t`` (0 before the first).
    """
    values = np.asarray(values, dtype=np.float64)
    d = values.shape[1] if values.ndim == 2 else 0
    values = values.reshape(len(times), d)
    cumulative = np.vstack([np.zeros((1, d)), np.cumsum(values, axis=0)])
    hi = np.searchsorted(times, ticks, side="right")
    parts = []
    for w in WINDOWS_S:
        lo = np.searchsorted(times, ticks - w, side="right")
        count = (hi - lo).astype(np.float64)
        mean = (cumulative[hi] - cumulative[lo]) / np.maximum(count, 1.0)[:, None]
        parts += [mean, count[:, None]]
    last = np.zeros((len(ticks), d))
    seen = hi > 0
    last[seen] = values[hi[seen] - 1]
    return np.hstack(parts + [last])


class ChannelBuffer:
    """The last ``max(WINDOWS_S)`` seconds of one channel's events, for online features."""

    def __init__(self, width: int, capacity: int = 4096) -> None:
        self.times = np.empty(capacity)
        self.values = np.empty((capacity, width))
        self.n = 0
        self._last: np.ndarray | None = None

    def add(self, t: float, vector: np.ndarray) -> None:
        if self.n == len(self.times):                     # a burst: grow (old events go at the next tick)
            self.times = np.concatenate([self.times, np.empty(len(self.times))])
            self.values = np.vstack([self.values, np.empty(self.values.shape)])
        self.times[self.n] = t
        self.values[self.n] = vector
        self.n += 1

    def features(self, tick: float) -> np.ndarray:
        """The features at ``tick``; drops events older than every window (the last one is kept)."""
        start = np.searchsorted(self.times[:self.n], tick - max(WINDOWS_S), side="right")
        if start >= self.n and self.n:
            self._last = self.values[self.n - 1].copy()
        if start:
            self.times[:self.n - start] = self.times[start:self.n]
            self.values[:self.n - start] = self.values[start:self.n]
            self.n -= start
        row = window_features(self.times[:self.n], self.values[:self.n], np.array([tick]))[0]
        if self.n == 0 and self._last is not None:        # nothing recent: the last event is still the last
            row[-self.values.shape[1]:] = self._last
        return row
