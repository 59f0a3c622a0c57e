"""Observers for agents: changes become ``observation(Name, true|false)`` percepts that trigger plans,
``.observations(Obs, PosAb)`` reads the current state, and a rule's ``post`` reaches the agent."""
from __future__ import annotations

from agentspeak.runtime import LocalRuntime
from detection.message import Message
from detection.taps import codec
from detection.taps.bag import BagRecorder
from .conftest import NAV_MODEL, REPAIR_RULES as RULES

OBSERVERS = """\
start_up_time: 0.5
setup:
  - type: hz
    topics:
      - name: /scan
        filter: {type: median, window_size: 5}
        states: [{state: nominal, frequency: {type: gauss, mean: 10, std_deviation: 1}}]
"""
AGENT = """\
!start.
+!start <- .observe("obs.yaml", [model("nav.yaml"), bag("run")]).
+observation(hz(scan), true) <- .print("scan ok").
+observation(hz(scan), false) <- .observations(Obs, PosAb); .print("fault ", Obs, " ", PosAb).
+!repair(C) <- .print("repair ", C); .stopMAS.
"""


def record_slowing_scan(path):
    store = codec.typestore()
    floats = store.types["std_msgs/msg/Float64"]
    rec = BagRecorder(path)
    rec.start(10**9)
    times = [1.05 + i / 10 for i in range(30)] + [4.05 + i / 3 for i in range(10)]
    for t in times:
        raw = bytes(store.serialize_cdr(floats(data=0.0), "std_msgs/msg/Float64"))
        rec.write(Message("/scan", int(t * 1e9), raw=raw), "std_msgs/msg/Float64")
    rec.close()


def test_a_plan_reacts_to_an_observation_found_by_the_observers(tmp_path):
    (tmp_path / "obs.yaml").write_text(OBSERVERS)
    (tmp_path / "nav.yaml").write_text(NAV_MODEL)
    (tmp_path / "nav.rules.yaml").write_text(RULES)
    record_slowing_scan(tmp_path / "run")
    source = tmp_path / "robot.asl"
    source.write_text(AGENT)
    lines: list[str] = []
    rt = LocalRuntime(printer=lambda name, text: lines.append(text))
    rt.add_agent("robot", AGENT, source_file=str(source))
    rt.run(timeout=30)
    assert lines == ["scan ok", "fault [~hz(scan)] [laser_driver]", "repair laser_driver"]


def test_bad_configuration_fails_the_goal_with_the_place(tmp_path):
    (tmp_path / "obs.yaml").write_text("setup:\n  - type: hzz\n")
    source = tmp_path / "robot.asl"
    program = '!start.\n+!start <- .observe("obs.yaml", [bag("run")]).\n-!start[error_msg(M)] <- .print(M).\n'
    lines: list[str] = []
    rt = LocalRuntime(printer=lambda name, text: lines.append(text))
    rt.add_agent("robot", program, source_file=str(source))
    rt.run(timeout=10)
    assert len(lines) == 1 and "obs.yaml:2:11: unknown observer type 'hzz'" in lines[0]
