"""Filters and the tests states apply: each filter's value and deviation, every nominal test, the t-test."""
from __future__ import annotations

import math
import random

import pytest
from scipy import stats

from detection.filters import FilterSpec
from detection.state_tests import NominalTest, QuantityTest, StudentT


def filled(spec: FilterSpec, values) -> "object":
    f = spec.make()
    for v in values:
        f.add(v)
    return f


@pytest.mark.parametrize("spec, values, value, deviation", [
    (FilterSpec("nofilter"), [1, 5, 3], 3, None),
    (FilterSpec("mean", window_size=2), [1, 5, 3], 4, math.sqrt(2)),
    (FilterSpec("mean"), [1, 5, 3], 3, 2.0),                                   # running mean: every sample
    (FilterSpec("median", window_size=3), [1, 100, 3, 2], 3, None),
    (FilterSpec("k_trimmed_mean", window_size=5, k_size=1), [1, 100, 3, 2, -50], 2, None),
    (FilterSpec("ewma", decay_rate=0.5), [0, 4, 8], 5, None),                  # 0 -> 2 -> 5
    (FilterSpec("mean", window_size=3, deviation_type="min_max"), [9, 1, 5, 3], 3, 4),
])
def test_filter_value_and_deviation(spec, values, value, deviation):
    f = filled(spec, values)
    assert f.value() == pytest.approx(value)
    if deviation is not None:
        assert f.deviation() == pytest.approx(deviation)


def test_an_empty_filter_knows_nothing():
    f = FilterSpec("mean", window_size=4).make()
    assert f.value() is None and f.deviation() is None and f.count == 0


@pytest.mark.parametrize("kind, params, accepted, rejected", [
    ("gauss", {"mean": 10, "std_deviation": 1}, [10, 7.1, 12.9], [6.9, 13.1]),
    ("exact", {"exact": 5}, [5], [5.01]),
    ("not", {"exact_not": 5}, [4], [5]),
    ("greater_than", {"greater_than": 5}, [5.1], [5, 4]),
    ("less_than", {"less_than": 5}, [4.9], [5]),
    ("in_between", {"lower_bound": 1, "upper_bound": 2}, [1, 1.5, 2], [0.9, 2.1]),
    ("not_in_between", {"lower_bound": 1, "upper_bound": 2}, [0.9, 2.1], [1, 2]),
])
def test_nominal_tests(kind, params, accepted, rejected):
    test = NominalTest(kind, tuple(params.items()))
    assert all(test.accepts(x) for x in accepted)
    assert not any(test.accepts(x) for x in rejected)


def test_nominal_value_tests_the_deviation_too():
    test = QuantityTest(NominalTest("in_between", (("lower_bound", 0), ("upper_bound", 10))),
                        (NominalTest("less_than", (("less_than", 1.0),)),))
    assert test.check(filled(FilterSpec("mean", window_size=4), [5, 5.1, 4.9, 5])) == (True, 5.0)
    assert test.check(filled(FilterSpec("mean", window_size=4), [1, 9, 2, 8]))[0] is False


def test_student_t_rejects_a_shifted_mean_and_accepts_an_unshifted_one():
    rng = random.Random(7)
    t = StudentT(true_mean=0.0, significance_level=0.05)
    healthy = [rng.gauss(0.0, 1.0) for _ in range(50)]
    shifted = [x + 1.0 for x in healthy]
    assert t.check(healthy)[0] is True
    assert t.check(shifted)[0] is False
    # the p-value is scipy's two-sided one-sample t-test
    assert t.p_value(shifted) == pytest.approx(stats.ttest_1samp(shifted, 0.0).pvalue)


def test_student_t_with_a_known_deviation():
    window = [0.3] * 9 + [0.2]
    known = StudentT(true_mean=0.0, significance_level=0.05, std_deviation=1.0)
    # mean 0.29 with sigma 1 over 10 samples: t = 0.917, well inside the band
    assert known.check(window)[0] is True
    assert StudentT(0.0, 0.05, std_deviation=0.1).check(window)[0] is False
    assert known.check([0.1]) is None            # one sample tells nothing
