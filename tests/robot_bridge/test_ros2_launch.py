"""``faultmas ros launch``'s supervisor: real node subprocesses, found in the graph, stopped cleanly."""
from __future__ import annotations

import pytest

pytest.importorskip("rclpy", reason="ROS 2 is an optional extra (pip install 'faultmas[ros2]')")

from robot_bridge.protocol import Action  # noqa: E402
from robot_bridge.ros2 import launch  # noqa: E402
from tests.ros_domain import ros_domain  # noqa: E402

DOMAIN = ros_domain(25)     # not the in-process graph's domain


def test_plan_rejects_bad_robot_names_and_faults():
    with pytest.raises(ValueError, match="distinct names"):
        launch.plan(["faulty", "faulty"])
    with pytest.raises(ValueError, match="unknown fault 'gremlins'"):
        launch.plan(["faulty"], fault="gremlins")


def test_plan_starts_every_node_of_every_robot_with_the_fault_on_the_first():
    specs = launch.plan(["faulty", "helper"], fault="encoders")
    assert {(s.robot, s.node) for s in specs} == {
        (r, n) for r in ("faulty", "helper")
        for n in ("kobuki_sim", "fault_injector", "motion_decomposer", "camera_sim", "visual_synthesizer")}
    faults = {s.robot: dict(s.params)["fault"] for s in specs if s.node == "fault_injector"}
    assert faults == {"faulty": "encoders", "helper": "none"}


def test_launched_nodes_serve_a_bridge_and_stop_cleanly():
    from robot_bridge.ros2.bridge import Ros2Bridge
    supervisor = launch.Supervisor(launch.plan(["faulty"], fault="encoders", camera=False), DOMAIN)
    supervisor.start()
    try:
        assert supervisor.wait_ready(timeout=30) == set()
        bridge = Ros2Bridge("faulty", domain_id=DOMAIN)
        bridge.setup(timeout=15)
        try:           # the fault given at launch (a -p parameter) is in force in the child processes
            completion = bridge.act(Action("move", (0.3,))).result(timeout=20)
            assert (completion.ok, completion.reason) == (False, "no_progress"), completion.detail
        finally:
            bridge.shutdown()
    finally:
        codes = supervisor.stop(grace=5.0)
    assert codes == [0, 0, 0]                     # SIGINT was enough: every node shut down cleanly
