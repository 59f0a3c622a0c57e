"""``python -m benchmarks inspect`` on tiny sizes, so it cannot rot (no timing is asserted)."""
from __future__ import annotations

from benchmarks.bench_inspect import SETUPS, _one, _put_cost


def test_every_setup_counts_to_the_end():
    for setup in SETUPS:
        wall, cpu = _one(setup, 2_000)   # raises unless the counter reached .stopMAS
        assert wall > 0 and cpu > 0


def test_a_put_of_a_real_mind_is_measured():
    cost, size, beliefs = _put_cost(3)
    assert cost > 0 and size > 1000 and beliefs > 5
