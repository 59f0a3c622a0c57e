"""The perfbugs benchmark in quick mode (no live team), so its harness cannot silently rot. No timing asserted."""
from __future__ import annotations

from benchmarks.bench_perfbugs import run


def test_quick_perfbugs_benchmark_prints_its_rows():
    table = run(quick=True)
    assert "training, smoke data" in table or "training, paper data" in table
    assert "scoring per component per tick, CPU, median" in table and "<= 1 ms" in table
    assert "skipped: --quick" in table
