"""The observer configuration: what it builds, and errors that name file, line, column and what was expected."""
from __future__ import annotations

import pytest

from agentspeak.errors import SourceError
from detection.config import load_observers
from detection.observers import KINDS

ALL_KINDS = """\
main_loop_rate: 20
start_up_time: 0.5
setup:
  - type: activated
    nodes: [{name: /laser_driver}]
  - type: resource
    nodes:
      - {name: amcl, process: amcl_node, states: [{state: ok, cpu: {type: less_than, less_than: 80}}]}
  - type: timeout
    topics: [{name: /cmd_vel, timeout: 0.5}]
  - type: hz
    start_up_time: 2
    topics:
      - name: /robot1/scan
        msg_type: sensor_msgs/msg/LaserScan
        states: [{state: ok, frequency: {type: gauss, mean: 10, std_deviation: 1}}]
  - type: timestamp
    topics: [{name: /scan, states: [{state: ok, delay: {type: less_than, less_than: 0.1}}]}]
  - type: timing
    topics:
      - {name_a: /scan, name_b: /pose, states: [{state: ok, delay: {type: less_than, less_than: 0.2}}]}
  - type: score
    topics:
      - {name: /pose_score, literal: score(localisation), field: data,
         states: [{state: ok, score: {type: greater_than, greater_than: 0.5}}]}
  - type: movement
    correlations:
      - source_a: {topic: /imu, field: angular_velocity.z, msg_type: sensor_msgs/msg/Imu}
        source_b: {topic: /wheel_odom, field: twist.twist.angular.z}
        differentiate: false
        filter: {type: mean, window_size: 50}
        states:
          - state: agree
            residual: {type: student_t, true_mean: 0, significance_level: 0.05}
"""


def test_one_observer_of_every_kind(write):
    config = load_observers(write("all.yaml", ALL_KINDS))
    assert [o.name for o in config.observers] == [
        "activated(laser_driver)", "resource(amcl)", "timeout(cmd_vel)", "hz(robot1_scan)", "timestamp(scan)",
        "timing(scan,pose)", "score(localisation)", "movement(imu,wheel_odom)"]
    assert {o.kind for o in config.observers} == set(KINDS)
    assert config.rate_hz == 20
    assert [o.start_up_time for o in config.observers][2:4] == [0.5, 2.0]
    assert config.topics["/robot1/scan"] == "sensor_msgs/msg/LaserScan" and config.topics["/scan"] is None
    assert config.decoded == {"/pose_score", "/imu", "/wheel_odom"} and config.stamped == {"/scan"}
    assert config.nodes == ["/laser_driver"] and config.processes == {"amcl": "amcl_node"}
    assert config.observers[-1].differentiate is False


@pytest.mark.parametrize("text, line, column, fragment", [
    ("setup:\n  - type: hzz\n    topics: []\n", 2, 11, "unknown observer type 'hzz'; expected one of: activated"),
    ("setup:\n  - type: hz\n    topics:\n      - name: /scan\n", 4, 9, "needs 'states'"),
    ("setup:\n  - type: hz\n    topics:\n      - name: /scan\n        states: [{state: a, freq: 1}]\n",
     5, 29, "unknown key 'freq' in a hz state; expected one of: state, number, healthy, frequency"),
    ("setup:\n  - type: hz\n    topics:\n      - name: /scan\n        filter: {type: median}\n"
     "        states: [{state: a, frequency: {type: exact, exact: 1}}]\n", 5, 17, "needs a window_size"),
    ("setup:\n  - type: hz\n    topics:\n      - name: /scan\n"
     "        states: [{state: a, frequency: {type: gauss, mean: ten, std_deviation: 1}}]\n",
     5, 60, "mean must be a number, not 'ten'"),
    ("setup:\n  - type: hz\n    topics:\n      - name: /scan\n"
     "        states: [{state: a, frequency: {type: student_t, true_mean: 1, significance_level: 5}}]\n",
     5, 92, "significance_level is between 0 and 1"),
    ("setup:\n  - type: hz\n    topics:\n      - {name: /Scan, states: [{state: a, frequency: {type: exact, exact: 1}}]}\n",
     4, 9, "hz(Scan) is not an observation literal"),
    ("setup:\n  - type: timeout\n    topics: [{name: /a}, {name: /a}]\n", 3, 26, "observation timeout(a) is emitted twice"),
    ("setup:\n  - type: hz\n    topics:\n      - {name: /s, msg_type: LaserScan, states: [{state: a, frequency: {type: exact, exact: 1}}]}\n",
     4, 30, "msg_type is a ROS 2 type such as std_msgs/msg/Float64"),
    ("setup: []\n", 1, 8, "setup lists no observer"),
    ("observers: []\n", 1, 1, "unknown key 'observers'"),
    ("setup:\n  - type: hz\n    topics: [{name: /s, states: [{state: a, frequency: {type: exact, exact: 1}}]\n", 4, None,
     "YAML syntax error"),
])
def test_bad_configuration_names_file_line_column_and_what_was_expected(write, text, line, column, fragment):
    path = write("bad.yaml", text)
    with pytest.raises(SourceError) as info:
        load_observers(path)
    err = info.value
    assert fragment in str(err)
    assert err.file == str(path) and err.line == line
    if column is not None:
        assert err.column == column
