"""The rule engine: the paper's four set tests, evaluation on change only, and every kind of action."""
from __future__ import annotations

import logging
import sys

import pytest

from agentspeak.errors import SourceError
from diagnosis.actions import ActionEnvironment
from diagnosis.loader import load_model
from diagnosis.rules import RuleEngine, load_rules

MODEL = """\
architecture: nav
nodes:
  laser: {pub: [scan]}
  amcl: {sub: [scan], pub: [pose]}
observations: [hz(scan), hz(pose)]
"""

RULES = """\
rules:
  - name: restart_laser
    posObs: [~hz(scan)]
    posPosAb: [laser]
    negPosAb: [amcl]
    call: restart
  - name: tell_the_team
    posObs: ["~hz(pose)"]
    negObs: [~hz(scan)]
    post: {agent: leader, literal: "+fault(amcl)"}
  - name: note
    posPosAb: [amcl]
    log: "amcl may be faulty ({possibly_faulty})"
"""


@pytest.fixture
def setup(write):
    model = load_model(write("nav.yaml", MODEL))
    rules = load_rules(write("nav.rules.yaml", RULES), model)
    calls, posts = [], []
    env = ActionEnvironment(callables={"restart": lambda ctx: calls.append(ctx) or "restarted"},
                            post=lambda agent, text: posts.append((agent, text)))
    return RuleEngine(rules, env), calls, posts


def test_four_set_tests(setup):
    engine, calls, posts = setup
    fired = engine.update({"hz(scan)": False}, {"laser"})
    assert [f.rule.name for f in fired] == ["restart_laser"] and fired[0].result == "restarted"
    assert calls[0].possibly_faulty == frozenset({"laser"})
    # negPosAb: amcl possibly faulty blocks restart_laser; posPosAb makes "note" fire
    assert [f.rule.name for f in engine.update({"hz(scan)": False}, {"laser", "amcl"})] == ["note"]
    # negObs: ~hz(scan) known blocks tell_the_team; unknown hz(scan) does not
    assert [f.rule.name for f in engine.update({"hz(scan)": False, "hz(pose)": False}, set())] == []
    assert [f.rule.name for f in engine.update({"hz(pose)": False}, set())] == ["tell_the_team"]
    assert posts == [("leader", "+fault(amcl)")]


def test_paper_semantics_a_missing_observation_blocks_nothing(write):
    """Section V: a rule fires unless Obs or a known PosAb contradicts it."""
    model = load_model(write("nav.yaml", MODEL))
    rules = {r.name: r for r in load_rules(write("nav.rules.yaml", RULES), model)}
    restart, tell = rules["restart_laser"], rules["tell_the_team"]
    assert restart.applies(frozenset(), frozenset({"laser"}))              # hz(scan) unknown: not contradicted
    assert not restart.applies(frozenset({"hz(scan)"}), frozenset({"laser"}))   # hz(scan) seen true
    assert restart.applies(frozenset({"hz(pose)"}), None)                  # no diagnosis yet: PosAb blocks nothing
    assert not restart.applies(frozenset(), frozenset())                   # laser known not possibly faulty
    assert not restart.applies(frozenset(), frozenset({"laser", "amcl"}))  # negPosAb contradicted
    assert tell.applies(frozenset({"hz(scan)"}), frozenset())              # negObs ~hz(scan) not in Obs
    assert not tell.applies(frozenset({"~hz(scan)"}), frozenset())


def test_strict_semantics_is_an_option_of_the_rules_file(write):
    model = load_model(write("nav.yaml", MODEL))
    strict = {r.name: r for r in load_rules(write("s.rules.yaml", "semantics: strict\n" + RULES), model)}
    assert all(r.strict for r in strict.values())
    assert not strict["restart_laser"].applies(frozenset(), frozenset({"laser"}))       # posObs must be in Obs
    assert strict["restart_laser"].applies(frozenset({"~hz(scan)"}), frozenset({"laser"}))
    assert not strict["restart_laser"].applies(frozenset({"~hz(scan)"}), None)          # unknown PosAb: empty
    engine = RuleEngine(strict.values(), ActionEnvironment(callables={"restart": lambda ctx: None}))
    assert engine.update({"hz(pose)": True}, {"laser"}) == []
    paper = RuleEngine(load_rules(write("p.rules.yaml", RULES), model),
                       ActionEnvironment(callables={"restart": lambda ctx: None}))
    assert [f.rule.name for f in paper.update({"hz(pose)": True}, {"laser"})] == ["restart_laser"]


def test_rules_run_only_when_obs_or_posab_change_and_once_per_change(setup):
    engine, calls, _ = setup
    assert len(engine.update({"hz(scan)": False}, ["laser"])) == 1
    assert engine.update({"hz(scan)": False}, ["laser"]) == []          # nothing changed
    assert engine.update({"hz(scan)": False}, ("laser",)) == []         # same sets, other containers
    assert len(engine.update({"hz(scan)": False, "hz(pose)": True}, ["laser"])) == 1   # Obs changed
    assert len(calls) == 2


def test_log_action_formats_the_message(setup, caplog):
    engine, _, _ = setup
    with caplog.at_level(logging.WARNING, logger="faultmas.diagnosis.rules"):
        fired = {f.rule.name: f for f in engine.update({}, {"amcl"})}
    assert fired["note"].result == "amcl may be faulty (amcl)"
    assert "amcl may be faulty (amcl)" in caplog.text


def test_command_action_runs_an_argument_list_without_a_shell(write):
    marker = write("marker.txt", "")
    rules = load_rules(write("r.yaml", f"""\
rules:
  - name: write_marker
    command: [{sys.executable}, -c, "import sys; open(sys.argv[1], 'w').write('ran; $HOME')", {marker}]
    timeout: 20
  - name: too_slow
    command: [{sys.executable}, -c, "import time; time.sleep(30)"]
    timeout: 0.5
"""))
    fired = RuleEngine(rules).update({"x": True}, set())
    assert marker.read_text() == "ran; $HOME"     # no shell: $HOME is not expanded
    assert fired[0].error is None
    assert "did not finish in 0.5 s" in fired[1].error


def test_set_parameter_goes_through_the_bridge_interface(write):
    class Bridge:
        def __init__(self):
            self.calls = []

        def set_parameter(self, node, name, value):
            self.calls.append((node, name, value))

    rules = load_rules(write("r.yaml", """\
rules:
  - name: slow_down
    set_parameter: {node: /controller, name: max_speed, value: 0.1}
"""))
    bridge = Bridge()
    RuleEngine(rules, ActionEnvironment(parameters=bridge)).update({}, {"c"})
    assert bridge.calls == [("/controller", "max_speed", 0.1)]
    fired = RuleEngine(rules).update({}, {"c"})   # no bridge: a clear error, not a crash
    assert "no ROS 2 parameter bridge" in fired[0].error


@pytest.mark.parametrize("text, line, fragment", [
    ("rules:\n  - name: a\n    posObs: [~hz(laser)]\n    log: x\n", 3, "'hz(laser)' is not an observation"),
    ("rules:\n  - name: a\n    posPosAb: [lidar]\n    log: x\n", 3, "'lidar' is not a component"),
    ("rules:\n  - name: a\n    log: x\n    call: f\n", 2, "exactly one action"),
    ("rules:\n  - name: a\n    command: ros2 run x\n", 3, "argument list"),
    ("rules:\n  - name: a\n    when: x\n    log: x\n", 3, "unknown key 'when'"),
    ("semantics: lenient\nrules: []\n", 1, "semantics is paper or strict, not 'lenient'"),
])
def test_bad_rules_name_file_line_and_reason(write, text, line, fragment):
    model = load_model(write("nav.yaml", MODEL))
    path = write("bad.rules.yaml", text)
    with pytest.raises(SourceError) as info:
        load_rules(path, model)
    assert (info.value.file, info.value.line) == (str(path), line)
    assert fragment in str(info.value)


def test_rules_live_next_to_their_model(write):
    model_path = write("nav.yaml", MODEL)
    from diagnosis.rules import rules_path_for
    assert rules_path_for(model_path) == model_path.with_name("nav.rules.yaml")
    write("nav.rules.yaml", RULES)
    assert [r.name for r in load_rules(rules_path_for(model_path), load_model(model_path))] == \
        ["restart_laser", "tell_the_team", "note"]
