"""The in-process stage breakdown of ``python -m benchmarks agents`` on a tiny count, so it cannot rot.

No timing is asserted (machines are noisy); what is checked is that the stages ran the real programs
to the end (``_stages`` raises when the sink did not answer ``done(N)``) and that they add up.
"""
from __future__ import annotations

import math

import pytest

from benchmarks.bench_agents_zenoh import SINK, _stages


def test_the_stages_of_a_tell_run_both_programs_and_add_up():
    stages = _stages(200, repeats=1)
    assert set(stages) == {"sender", "decode", "content", "sink", "reasoning"}
    assert all(math.isfinite(value) and value > 0 for value in stages.values()), stages
    assert math.isclose(stages["sink"], stages["decode"] + stages["content"] + stages["reasoning"])


def test_a_sink_that_never_answers_is_reported_not_timed(monkeypatch):
    import benchmarks.bench_agents_zenoh as bench

    monkeypatch.setattr(bench, "SINK", SINK.replace(".send(S, tell, done(N))", ".print(N)"))
    with pytest.raises(RuntimeError, match=r"expected done\(50\)"):
        _stages(50, repeats=1)
