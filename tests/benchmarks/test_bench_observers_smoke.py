"""The replay parts of ``python -m benchmarks observers`` on a small run, so the benchmark cannot rot.

No timing is asserted: what is checked is that every observer kind decided something on the synthetic
run, the same in memory and from the MCAP bag, so the figures measure real work."""
from __future__ import annotations

from benchmarks.bench_observers import bag_rate, replay_rate, synthetic


def test_the_synthetic_run_exercises_every_kind_in_memory_and_from_a_bag(tmp_path):
    messages = synthetic(6_000)
    rate, known = replay_rate(messages, tmp_path)
    assert known == 13 and rate > 0           # all 13 observations of the 8 kinds became known
    assert bag_rate(messages, tmp_path) > 0
