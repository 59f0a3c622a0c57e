"""Observations -> diagnoser (architecture model) -> rules: diagnoses on change only, the paper's rule semantics."""
from __future__ import annotations

import pytest

from detection.config import load_observers
from detection.observation import Observation
from detection.pipeline import Pipeline
from diagnosis.actions import ActionEnvironment
from diagnosis.loader import load_model
from diagnosis.rules import load_rules

from .conftest import NAV_MODEL, merged, stream

RULES = """\
rules:
  - name: slow_laser
    posObs: [~hz(scan)]
    posPosAb: [laser_driver]
    set_parameter: {node: /laser_driver, name: rate, value: 10.0}
"""
OBSERVERS = """\
start_up_time: 1
setup:
  - type: hz
    topics:
      - name: /scan
        filter: {type: median, window_size: 5}
        states: [{state: ok, frequency: {type: gauss, mean: 10, std_deviation: 1}}]
      - name: /pose
        filter: {type: median, window_size: 5}
        states: [{state: ok, frequency: {type: gauss, mean: 10, std_deviation: 1}}]
"""


class Parameters:
    def __init__(self):
        self.calls = []

    def set_parameter(self, node, name, value):
        self.calls.append((node, name, value))


@pytest.fixture
def pipeline(write):
    model = load_model(write("nav.yaml", NAV_MODEL))
    params = Parameters()
    pipe = Pipeline(model, load_rules(write("nav.rules.yaml", RULES), model), ActionEnvironment(parameters=params))
    yield pipe, params
    pipe.close()


def test_a_slow_publisher_is_blamed_and_the_rule_reacts(pipeline, write):
    pipe, params = pipeline
    updates = []
    pipe.add_listener(updates.append)
    observers = load_observers(write("obs.yaml", OBSERVERS)).build()
    observers.start(0)
    msgs = merged(stream("/scan", 10, 0.01, 3), stream("/scan", 3, 3, 8), stream("/pose", 10, 0.02, 8))
    for m in msgs:
        pipe.observe(observers.feed(m))
    pipe.observe(observers.advance(int(8e9)))
    assert [sorted(o.literal for o in u.changed) for u in updates] == [["hz(pose)", "hz(scan)"], ["~hz(scan)"]]
    assert updates[0].diagnoses == ((),) and updates[0].possibly_faulty == frozenset()
    assert updates[1].diagnoses == (("laser_driver",),) and updates[1].possibly_faulty == {"laser_driver"}
    assert [f.rule.name for f in updates[1].fired] == ["slow_laser"]
    assert params.calls == [("/laser_driver", "rate", 10.0)]
    assert updates[1].to_json()["obs"] == ["hz(pose)", "~hz(scan)"]


def test_diagnosis_runs_only_when_an_observation_flips(pipeline, monkeypatch):
    pipe, _ = pipeline
    calls = []
    real = pipe._diagnoser.diagnose
    monkeypatch.setattr(pipe._diagnoser, "diagnose", lambda *a, **k: calls.append(a) or real(*a, **k))
    assert pipe.observe([Observation.of("~hz(scan)", 1.0, 3.0)]) is not None
    for t in range(2, 50):                      # the same verdict again and again: no new diagnosis
        assert pipe.observe([Observation.of("~hz(scan)", float(t), 2.9)]) is None
    assert pipe.observations["hz(scan)"].measured == 2.9     # the latest value is still kept
    pipe.observe([Observation.of("hz(scan)", 60.0, 10.0)])
    assert len(calls) == 2


def test_observations_outside_the_model_reach_the_rules_but_not_the_diagnoser(write, caplog):
    model = load_model(write("nav.yaml", NAV_MODEL))
    fired = []
    rules = load_rules(write("r.yaml", "rules:\n  - {name: hot, posObs: [~resource(amcl)], call: note}\n"))
    pipe = Pipeline(model, rules, ActionEnvironment(callables={"note": fired.append}))
    update = pipe.observe([Observation.of("~resource(amcl)", 1.0, 95.0, source="learned")])
    assert update.diagnoses == ((),) and len(fired) == 1
    assert "resource(amcl) is not declared by model nav" in caplog.text
    pipe.close()


def test_without_a_model_rules_see_an_unknown_posab(write):
    fired = []
    rules = load_rules(write("r.yaml", "rules:\n  - {name: r, posObs: [~hz(scan)], posPosAb: [laser], call: f}\n"))
    pipe = Pipeline(rules=rules, environment=ActionEnvironment(callables={"f": fired.append}))
    update = pipe.observe([Observation.of("~hz(scan)", 1.0)])
    assert update.possibly_faulty is None and update.diagnoses is None and len(fired) == 1


def test_observation_literals():
    o = Observation.of("~ movement(imu, wheel_odom)", 3.5, 0.4, state=None, source="movement")
    assert (o.name, o.holds, o.literal) == ("movement(imu,wheel_odom)", False, "~movement(imu,wheel_odom)")
    assert o.to_json()["measured"] == 0.4
    with pytest.raises(ValueError, match="not an observation literal"):
        Observation.of("hz(/scan)", 0.0)
