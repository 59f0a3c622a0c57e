"""The tests a state applies to a filtered quantity: nominal tests and a two-sided Student t-test.

Nominal (tug_observers' names): ``gauss`` (within mean ± n_sigma·std_deviation, n_sigma 3 by
default), ``exact``, ``not``, ``greater_than``, ``less_than``, ``in_between``, ``not_in_between``;
applied to the filtered value, and in the long form ``nominal_value`` also to the deviation.
``student_t``: the window's mean against ``true_mean`` at ``significance_level`` (scipy.stats); with
``std_deviation`` given the population deviation is taken as known instead of estimated.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from detection.filters import Filter

NOMINAL = {  # type -> its parameters (all numbers)
    "gauss": ("mean", "std_deviation"), "exact": ("exact",), "not": ("exact_not",),
    "greater_than": ("greater_than",), "less_than": ("less_than",),
    "in_between": ("lower_bound", "upper_bound"), "not_in_between": ("lower_bound", "upper_bound"),
}
OPTIONAL = {"gauss": ("n_sigma",)}


@dataclass(frozen=True)
class NominalTest:
    type: str
    params: tuple[tuple[str, float], ...]

    def __post_init__(self) -> None:
        if self.type not in NOMINAL:
            raise ValueError(f"unknown test {self.type!r}; expected one of: {', '.join(NOMINAL)}")

    def accepts(self, x: float) -> bool:
        p = dict(self.params)
        t = self.type
        if t == "gauss":
            return abs(x - p["mean"]) <= p.get("n_sigma", 3.0) * p["std_deviation"]
        if t == "exact":
            return x == p["exact"]
        if t == "not":
            return x != p["exact_not"]
        if t == "greater_than":
            return x > p["greater_than"]
        if t == "less_than":
            return x < p["less_than"]
        inside = p["lower_bound"] <= x <= p["upper_bound"]
        return inside if t == "in_between" else not inside


@dataclass(frozen=True)
class QuantityTest:
    """What one state requires of one quantity; ``check`` returns (passed, measured) or None (unknown)."""
    value: NominalTest | None = None              # on the filtered value
    deviation: tuple[NominalTest, ...] = ()       # nominal_value's deviation tests, all must pass
    student_t: "StudentT | None" = None

    def check(self, f: Filter) -> tuple[bool, float] | None:
        if self.student_t is not None:
            return self.student_t.check(f.window())
        x = f.value()
        if x is None:
            return None
        ok = self.value.accepts(x) if self.value is not None else True
        if ok and self.deviation:
            d = f.deviation()
            if d is None:
                return None
            ok = all(t.accepts(d) for t in self.deviation)
        return ok, x


@dataclass(frozen=True)
class StudentT:
    true_mean: float
    significance_level: float
    std_deviation: float | None = None
    min_samples: int = 2

    def p_value(self, window: Sequence[float]) -> float | None:
        """Two-sided p-value of "the window's mean is true_mean"; None with too few samples."""
        from scipy import stats

        n = len(window)
        if n < max(self.min_samples, 2):
            return None
        mean = math.fsum(window) / n
        sd = self.std_deviation
        if sd is None:       # estimated from the window: the one-sample t-test (scipy.stats.ttest_1samp's p)
            sd = math.sqrt(math.fsum((x - mean) ** 2 for x in window) / (n - 1))
            if sd == 0.0:    # a constant window: its mean is exactly known
                return 1.0 if mean == self.true_mean else 0.0
        t = (mean - self.true_mean) / (sd / math.sqrt(n))
        # the t distribution's tail from scipy.stats; the statistic by hand: ttest_1samp's input checks
        # cost ~1 ms a call, 20x the rest of an evaluation
        return float(2.0 * stats.t.sf(abs(t), df=n - 1))

    def check(self, window: Sequence[float]) -> tuple[bool, float] | None:
        """Accepted when the p-value is at least the significance level; measured is the window mean."""
        p = self.p_value(window)
        if p is None:
            return None
        return p >= self.significance_level, math.fsum(window) / len(window)
