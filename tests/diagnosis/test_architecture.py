"""The paper's software-architecture models: each observation kind's formula and fault propagation."""
from __future__ import annotations

import pytest

from diagnosis.engine import Diagnoser
from diagnosis.loader import load_model

NAV = """\
architecture: nav
nodes:
  laser: {pub: [scan]}
  base: {pub: [odom]}
  imu_driver: {pub: [imu]}
  amcl: {sub: [scan, odom], pub: [pose]}
  planner: {sub: [pose], pub: [cmd_vel]}
observations:
  - activated(amcl)
  - resource(planner)
  - hz(scan)
  - timeout(odom)
  - timestamp(pose)
  - score(pose)
  - timing(scan, pose)
  - movement(odom, imu)
"""


@pytest.fixture
def nav(write):
    return Diagnoser(load_model(write("nav.yaml", NAV)))


def test_only_nodes_are_candidates(nav):
    assert nav.model.components == ("laser", "base", "imu_driver", "amcl", "planner")


@pytest.mark.parametrize("failed, expected", [
    ("activated(amcl)", [["amcl"]]),                        # !obs -> AB(n)
    ("resource(planner)", [["planner"]]),
    ("hz(scan)", [["laser"]]),                              # !obs -> AB(m), AB(scan) -> AB(laser)
    ("timeout(odom)", [["base"]]),
    ("timestamp(pose)", [["laser"], ["base"], ["amcl"]]),   # AB(pose) -> AB(amcl) | AB(scan) | AB(odom)
    ("score(pose)", [["laser"], ["base"], ["amcl"]]),
    ("timing(scan,pose)", [["laser"], ["base"], ["amcl"]]),  # !obs -> AB(scan) | AB(pose)
])
def test_each_observation_kind_uses_the_papers_formula(nav, failed, expected):
    assert nav.diagnose({failed: False}).diagnoses == expected


def test_true_observations_constrain_nothing(nav):
    assert nav.diagnose({name: True for name in nav.model.observables}).diagnoses == [[]]


def test_two_failed_observations_need_a_common_or_a_double_explanation(nav):
    result = nav.diagnose({"hz(scan)": False, "timeout(odom)": False, "timestamp(pose)": False})
    assert result.diagnoses == [["laser", "base"]]
    result = nav.diagnose({"hz(scan)": False, "activated(amcl)": False})
    assert result.diagnoses == [["laser", "amcl"]]


def test_imu_odometry_movement_example(nav, write):
    # the odometry says the robot moves, the IMU does not agree: odometry, IMU, or the movement itself
    assert nav.diagnose({"movement(odom,imu)": False}).diagnoses == [["base"], ["imu_driver"]]
    # the odometry topic is known fine at the node level? only a failed hz/timeout would add AB(odom);
    # with the base also failing its timeout, one fault (base) explains both
    assert nav.diagnose({"movement(odom,imu)": False, "timeout(odom)": False}).diagnoses == [["base"]]
    as_candidate = load_model(write("nav2.yaml", NAV + "assumptions:\n  movement: candidate\n"))
    result = Diagnoser(as_candidate).diagnose({"movement(odom,imu)": False})
    assert result.diagnoses == [["base"], ["imu_driver"], ["movement"]]
