"""Loading models: system descriptions, architecture models, .bench netlists, and their error messages."""
from __future__ import annotations

import pytest

from agentspeak.errors import SourceError
from diagnosis.bench import parse_bench, simulate
from diagnosis.loader import load_model



GOOD = """\
system: lamp
components: [bulb, switch]
observations: [on, lit]
variables: [current]
behaviour:
  - "!AB(switch) -> (current <-> on)"
  - "!AB(bulb) -> (lit <-> current)"
"""


def test_system_description_loads_components_in_order(write):
    model = load_model(write("lamp.yaml", GOOD))
    assert model.components == ("bulb", "switch")
    assert set(model.observables) == {"on", "lit"}


@pytest.mark.parametrize("text, line, fragment", [
    (GOOD.replace("AB(bulb)", "AB(bulp)"), 7, "unknown component 'bulp'"),
    (GOOD.replace("(lit <-> current)", "(lit <-> curent)"), 7, "unknown proposition 'curent'"),
    (GOOD.replace("(current <-> on)", "(current <-> on"), 6, "formula ends too early"),
    (GOOD.replace("variables: [current]", "variables: [current, bulb]"), 4, "already declared as component"),
    (GOOD + "colour: red\n", 8, "unknown key 'colour'"),
    (GOOD.replace("components: [bulb, switch]", "components: [bulb, switch"), 3, "YAML syntax error"),
])
def test_bad_system_descriptions_name_file_line_and_reason(write, text, line, fragment):
    path = write("lamp.yaml", text)
    with pytest.raises(SourceError) as info:
        load_model(path)
    assert info.value.file == str(path)
    assert info.value.line == line
    assert fragment in str(info.value)


ARCH = """\
architecture: nav
nodes:
  laser: {pub: [scan]}
  amcl: {sub: [scan, odom], pub: [pose]}
  base: {pub: [odom]}
observations:
  - hz(scan)
  - hz(pose)
"""


@pytest.mark.parametrize("text, line, fragment", [
    (ARCH.replace("sub: [scan, odom]", "sub: [scan, odm]"), 4, "subscribes to topic 'odm' but no node publishes it"),
    (ARCH.replace("hz(pose)", "hz(map)"), 8, "topic 'map' is published by no node"),
    (ARCH.replace("hz(pose)", "speed(pose)"), 8, "unknown observation kind 'speed'"),
    (ARCH.replace("hz(pose)", "timing(pose)"), 8, "timing takes 2 argument(s)"),
    (ARCH.replace("hz(pose)", "activated(lidar)"), 8, "unknown node 'lidar'"),
])
def test_bad_architecture_models_name_file_line_and_reason(write, text, line, fragment):
    path = write("nav.yaml", text)
    with pytest.raises(SourceError) as info:
        load_model(path)
    assert (info.value.file, info.value.line) == (str(path), line)
    assert fragment in str(info.value)


def test_bench_parse_matches_the_readme_counts_of_c17(data_dir):
    net = parse_bench(data_dir / "c17.bench")
    assert (len(net.inputs), len(net.outputs), len(net.gates)) == (5, 2, 6)
    values = simulate(net, {x: True for x in net.inputs})
    # by hand: G10 = G11 = 0, G16 = G19 = 1, G22 = nand(0, 1) = 1, G23 = nand(1, 1) = 0
    assert (values["G22gat"], values["G23gat"]) == (True, False)


@pytest.mark.parametrize("text, line, fragment", [
    ("INPUT(a)\nOUTPUT(y)\ny = nand(a, b)\n", 3, "reads signal 'b'"),
    ("INPUT(a)\nOUTPUT(y)\ny = mux(a, a)\n", 3, "unknown gate type 'mux'"),
    ("INPUT(a)\nOUTPUT(z)\ny = not(a)\n", 2, "OUTPUT(z) is not defined"),
    ("INPUT(a)\nOUTPUT(y)\ny = not(a)\ny = buf(a)\n", 4, "defined twice"),
    ("INPUT(a)\nOUTPUT(y)\ny = and(a, z)\nz = and(a, y)\n", 4, "combinational loop through"),
    ("INPUT(a)\nthis is not bench\n", 2, "expected INPUT(x)"),
])
def test_bad_netlists_name_file_line_and_reason(write, text, line, fragment):
    path = write("bad.bench", text)
    with pytest.raises(SourceError) as info:
        load_model(path)
    assert (info.value.file, info.value.line) == (str(path), line)
    assert fragment in str(info.value)


def test_iscas_counts_match_the_readme(iscas):
    for name, gates in [("c432", 160), ("c880", 383), ("c7552", 3512)]:
        assert len(load_model(iscas / f"{name}.bench").components) == gates
