"""The faultmas side of the AgentSpeak benchmark on a tiny count, so the harness cannot silently rot.

No timing is asserted (speed lives in ``python -m benchmarks asl``); the baseline venv is not used.
"""
from __future__ import annotations

import dataclasses

import pytest

from agentspeak.errors import SourceError
from benchmarks.asl_workload import rewrite_initial_belief
from benchmarks.bench_asl import ASL_DIR, WORKLOADS, Result, _pyas_line, render, run_faultmas

pytestmark = pytest.mark.skipif(not (ASL_DIR / "count.asl").exists(), reason=f"{ASL_DIR} is missing")

TINY_COUNT = dataclasses.replace(WORKLOADS["count"], quick={"max": 321})


def test_tiny_count_runs_in_a_child_and_its_line_is_verified():
    result = run_faultmas(TINY_COUNT, quick=True)
    assert result.error == ""
    assert result.detail["last_line"] == "[count] count done 321"
    assert result.detail["agents"] == {"count": {"plans": 2, "rules": 0}}
    assert len(result.seconds) == 1 and result.seconds[0] >= 0.0
    assert result.best == result.seconds[0]
    assert result.peak_rss_kb > 0
    assert result.detail["interpreter"]                      # compiled or pure Python: said in the table


def test_from_source_runs_with_the_compiled_interpreter_switched_off():
    result = run_faultmas(TINY_COUNT, quick=True, from_source=True)
    assert result.error == "" and result.detail["interpreter"] == "pure Python"


def test_a_wrong_last_line_is_a_failure_not_a_number():
    wrong = dataclasses.replace(TINY_COUNT, expected=lambda sizes: f"[count] count done {sizes['max'] + 1}")
    result = run_faultmas(wrong, quick=True)
    assert result.best is None
    assert "expected '[count] count done 322'" in result.error
    assert "'[count] count done 321'" in result.error


def test_scaling_a_missing_size_belief_names_the_file():
    with pytest.raises(SourceError, match="count.asl") as info:
        rewrite_initial_belief("max(100000).\n", "size", "4", "count.asl")
    assert "size(...)" in str(info.value)
    assert rewrite_initial_belief("max(100000).\n!count(0).\n", "max", "7") == "max(7).\n!count(0).\n"


def test_python_agentspeak_lines_compare_without_prefix_and_spacing():
    assert _pyas_line("count count done  100000") == "count done 100000"
    assert _pyas_line("[count] count done 100000") == "count done 100000"
    assert _pyas_line("count count done  99999") != _pyas_line("[count] count done 100000")


def test_table_says_baseline_unavailable_and_lists_failures():
    results = {name: Result(seconds=[0.5], peak_rss_kb=2048) for name in WORKLOADS}
    results["fib"] = Result(error="last line None, expected '[fib] fib 20 6765'")
    table = render(results, None, "pip install failed: no network", quick=False)
    assert "baseline unavailable" in table and "no network" in table
    fib_row = next(line for line in table.splitlines() if line.startswith("fib"))
    assert "FAILED" in fib_row
    assert "FAILED fib (rules), faultmas: last line None" in table
    count_row = next(line for line in table.splitlines() if line.startswith("count"))
    assert "200,000 (0.500 s)" in count_row and "yes" in count_row


def test_table_shows_the_from_source_column_and_judges_the_default_install():
    results = {name: Result(seconds=[0.5], peak_rss_kb=2048, detail={"interpreter": "compiled (Cython, 20 modules)"})
               for name in WORKLOADS}
    source = {name: Result(seconds=[1.0], peak_rss_kb=2048) for name in WORKLOADS}
    table = render(results, None, "no network", quick=False, source=source)
    assert "from source (CPU)" in table.splitlines()[0]
    count_row = next(line for line in table.splitlines() if line.startswith("count"))
    assert "200,000 (0.500 s)" in count_row and "100,000 (1.000 s)" in count_row and "yes" in count_row
    assert "faultmas interpreter: compiled (Cython, 20 modules)" in table


def test_quick_scaling_keeps_the_fill_run_query_free():
    fill, join = WORKLOADS["beliefs-fill"], WORKLOADS["beliefs"]
    assert fill.sets(quick=True)["queries"] == 0 and fill.sets(quick=False) == {"queries": 0}
    assert join.sets(quick=True)["queries"] > 0 and join.sets(quick=False) == {}
    assert fill.sizes(quick=True)["size"] == join.sizes(quick=True)["size"]
