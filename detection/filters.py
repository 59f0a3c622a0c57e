"""Filters on an observer's raw signal (tug_observers' set): none, mean (window or running), median,
k-trimmed mean and EWMA, each with a deviation (standard deviation or min-max spread).

``add`` is called per message and only stores (a deque append, an EWMA step); the filtered value and
deviation are computed when the observer is evaluated (a few times per second), never per message.
``window()`` is the sample the Student t-test runs on.
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from statistics import median
from typing import Sequence

DEVIATIONS = ("std_deviation", "min_max")


@dataclass(frozen=True)
class FilterSpec:
    """A filter's configuration; ``make()`` builds a fresh one per quantity."""
    type: str = "nofilter"                 # nofilter | mean | median | k_trimmed_mean | ewma
    window_size: int | None = None         # None for mean: running mean over every sample
    decay_rate: float = 0.05               # ewma: x = x * (1 - decay_rate) + new * decay_rate
    k_size: int = 0                        # k_trimmed_mean: drop the k smallest and k largest
    deviation_type: str = "std_deviation"

    def make(self) -> "Filter":
        return Filter(self)


TYPES = ("nofilter", "mean", "median", "k_trimmed_mean", "ewma")


class Filter:
    """One quantity's filter state."""

    __slots__ = ("spec", "_window", "_count", "_sum", "_sumsq", "_min", "_max", "_ewma", "_last")

    def __init__(self, spec: FilterSpec) -> None:
        self.spec = spec
        size = spec.window_size
        if size is None and spec.type in ("nofilter",):
            size = 1
        self._window: deque[float] | None = deque(maxlen=size) if size is not None else None
        self._count = 0
        self._sum = self._sumsq = 0.0          # running mean (no window) and its deviation
        self._min = math.inf
        self._max = -math.inf
        self._ewma: float | None = None
        self._last: float | None = None

    def add(self, x: float) -> None:
        self._count += 1
        self._last = x
        if self._window is not None:
            self._window.append(x)
        else:
            self._sum += x
            self._sumsq += x * x
            if x < self._min:
                self._min = x
            if x > self._max:
                self._max = x
        if self.spec.type == "ewma":
            r = self.spec.decay_rate
            self._ewma = x if self._ewma is None else self._ewma * (1.0 - r) + x * r

    def reset(self) -> None:
        self.__init__(self.spec)

    @property
    def count(self) -> int:
        """Samples added since the start (or the last reset)."""
        return self._count

    def window(self) -> Sequence[float]:
        """The samples in the window (empty for a running mean, which keeps none)."""
        return tuple(self._window) if self._window is not None else ()

    def value(self) -> float | None:
        """The filtered value; None before the first sample."""
        if self._count == 0:
            return None
        kind = self.spec.type
        if kind == "nofilter":
            return self._last
        if kind == "ewma":
            return self._ewma
        if self._window is None:                 # running mean
            return self._sum / self._count
        w = self._window
        if kind == "mean":
            return math.fsum(w) / len(w)
        if kind == "median":
            return float(median(w))
        k = self.spec.k_size
        kept = sorted(w)[k:len(w) - k] if len(w) > 2 * k else [float(median(w))]
        return math.fsum(kept) / len(kept)

    def deviation(self) -> float | None:
        """Standard deviation (sample, n-1) or max - min of the window; None with fewer than 2 samples."""
        if self._window is None:
            n = self._count
            if n < 2:
                return None
            if self.spec.deviation_type == "min_max":
                return self._max - self._min
            mean = self._sum / n
            return math.sqrt(max(self._sumsq - n * mean * mean, 0.0) / (n - 1))
        w = self._window
        if len(w) < 2:
            return None
        if self.spec.deviation_type == "min_max":
            return max(w) - min(w)
        mean = math.fsum(w) / len(w)
        return math.sqrt(math.fsum((x - mean) ** 2 for x in w) / (len(w) - 1))
