"""The IMU experiment on real rclpy nodes in other processes: a short run, in a ROS domain of its own.

kobuki_sim, fault_injector and the odometry node run as processes; the fault is set through the
injector's parameter service, and the rule's set_parameter reaches the odometry node's use_imu.
"""
from __future__ import annotations

import contextlib
import io
import json

import pytest

pytest.importorskip("rclpy", reason="ROS 2 is an optional extra (pip install 'faultmas[ros2]')")

from agents.cli import main as faultmas  # noqa: E402
from tests.ros_domain import ros_domain  # noqa: E402

DOMAIN = ros_domain(61)


def test_a_short_ros2_run_detects_the_fault_and_switches_the_real_node():
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = faultmas(["experiment", "imu", "--bridge", "ros2", "--fault", "imu_stuck", "--runs", "1",
                         "--duration", "25", "--seed", "1", "--domain-id", str(DOMAIN), "--json"])
    assert code == 0, err.getvalue()
    figures = json.loads(out.getvalue())["faults"]["imu_stuck"]
    assert figures["detected"] == 1 and figures["false_switches"] == 0, err.getvalue()
    assert figures["reduction_vs_always_imu_pct"]["mean"]["median"] < 0      # as in the embedded run
    assert 0 < figures["cpu_share_max"] < 0.05
    assert "use_imu" in err.getvalue() or "switched at" in err.getvalue()
