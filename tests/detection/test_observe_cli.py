"""``faultmas observe`` on bad input: one clear line naming the file (and line), exit 2, never a traceback;
and the output of a replay for a user (one line per change) and a script (JSON)."""
from __future__ import annotations

import json
import shutil

import pytest

from agents.cli import main
from detection.message import Message
from detection.taps import codec
from detection.taps.bag import BagRecorder

GOOD = """\
start_up_time: 0.5
setup:
  - type: hz
    topics:
      - name: /scan
        states: [{state: nominal, frequency: {type: gauss, mean: 10, std_deviation: 1}}]
  - type: score
    topics:
      - {name: /battery, states: [{state: ok, score: {type: greater_than, greater_than: 11}}]}
"""


@pytest.fixture
def bag(tmp_path):
    """A bag as a tap records it: /scan at 10 Hz then 3 Hz, /battery with one undecodable message."""
    store = codec.typestore()
    floats = store.types["std_msgs/msg/Float64"]
    rec = BagRecorder(tmp_path / "run")
    rec.start(10**9)

    def write(topic, t, value):
        raw = bytes(store.serialize_cdr(floats(data=value), "std_msgs/msg/Float64"))
        rec.write(Message(topic, int(t * 1e9), raw=raw), "std_msgs/msg/Float64")
    for i in range(30):
        write("/scan", 1.05 + i / 10, 0.0)
    for i in range(10):
        write("/scan", 4.05 + i / 3, 0.0)
    for i in range(10):
        write("/battery", 1.0 + i / 5, 12.0)
    rec.write(Message("/battery", int(3.5e9), raw=b"\x00\x01"), "std_msgs/msg/Float64")
    rec.close()
    return tmp_path / "run"


def test_replay_prints_one_line_per_change_and_reports_unreadable_messages(write, bag, capsys):
    config = write("obs.yaml", GOOD)
    assert main(["observe", str(config), "--bag", str(bag)]) == 0
    out, err = capsys.readouterr()
    lines = out.splitlines()
    assert len(lines) == 2, out
    assert "hz(scan)=10 Hz, score(battery)=12 | diagnoses -" in lines[0]
    assert "~hz(scan)=" in lines[1]
    assert "score(battery): 1 unreadable message(s) dropped" in err
    assert main(["observe", str(config), "--bag", str(bag), "--json"]) == 0
    objects = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert objects[-1]["obs"] == ["score(battery)", "~hz(scan)"]


@pytest.mark.parametrize("case, fragment", [
    ("malformed", "obs.yaml:4:11: unknown observer type 'hzz'"),
    ("missing bag", "nope: no such bag"),
    ("truncated bag", "cannot read this bag"),
    ("bad model", "nav.yaml:1:1: a model starts with"),
])
def test_bad_input_is_one_clear_line_and_exit_2(write, bag, tmp_path, capsys, case, fragment):
    config = write("obs.yaml", GOOD)
    args = ["observe", str(config), "--bag", str(bag)]
    if case == "malformed":
        write("obs.yaml", "setup:\n  - type: hz\n    topics: []\n  - type: hzz\n    topics: []\n")
    elif case == "missing bag":
        args[-1] = str(tmp_path / "nope")
    elif case == "truncated bag":
        mcap = next(bag.glob("*.mcap"))
        data = mcap.read_bytes()
        cut = tmp_path / "cut"
        shutil.copytree(bag, cut)
        (cut / mcap.name).write_bytes(data[: len(data) * 2 // 3])
        args[-1] = str(cut)
    else:
        args += ["--model", str(write("nav.yaml", "nodes: {}\n"))]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert fragment in err and "Traceback" not in err


def test_an_unknown_topic_type_is_named_before_anything_starts(write, capsys):
    pytest.importorskip("rclpy")
    config = write("obs.yaml", "setup:\n  - type: hz\n    topics:\n      - {name: /scan, msg_type: nav_msgs/msg/Nope,\n"
                               "         states: [{state: a, frequency: {type: exact, exact: 1}}]}\n")
    assert main(["observe", str(config), "--domain-id", "99", "--duration", "1"]) == 2
    err = capsys.readouterr().err
    assert "unknown topic type 'nav_msgs/msg/Nope'" in err and "Traceback" not in err


def test_the_status_table_shows_each_observer_the_diagnoses_and_the_rules(write, bag):
    import io

    from detection.session import open_session, replay_bag
    from detection.status import StatusTable

    model = write("nav.yaml", "architecture: nav\nnodes:\n  laser: {pub: [scan]}\n  battery: {pub: [battery]}\n"
                              "observations: [hz(scan), score(battery)]\n")
    write("nav.rules.yaml", "rules:\n  - {name: restart_laser, posObs: [~hz(scan)], posPosAb: [laser], log: restart}\n")
    session = open_session(write("obs.yaml", GOOD), model)
    out = io.StringIO()
    table = StatusTable(session.observers, out)
    session.pipeline.add_listener(table.record)
    replay_bag(session, bag)
    table.draw()
    screen = out.getvalue()
    assert screen.startswith("\x1b[H\x1b[2J")                    # redrawn in place
    rows = {line.split()[0]: line for line in screen.splitlines()[1:3]}
    assert "FAULT" in rows["hz(scan)"] and "Hz" in rows["hz(scan)"]
    assert "ok" in rows["score(battery)"] and "(1 unreadable)" in rows["score(battery)"]
    assert "diagnoses: {laser}" in screen and "restart_laser" in screen
    session.close()
