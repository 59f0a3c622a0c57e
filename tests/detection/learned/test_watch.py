"""The architecture model made from the discovered components: the diagnoser blames the node whose
``resource`` observation fails, through the observers' pipeline."""
from __future__ import annotations

from detection.learned.ros_tap import Component
from detection.learned.watch import architecture_yaml, topic_atom
from detection.observation import Observation
from detection.pipeline import Pipeline
from diagnosis.architecture_yaml import load_architecture
from diagnosis.yaml_source import YamlSource


def test_a_failed_resource_observation_names_its_component():
    components = [
        Component("faulty_kobuki_sim", "/faulty", "kobuki_sim", inputs=["/faulty/commands/velocity"],
                  outputs=["/faulty/odom", "/faulty/sensors/core"]),
        Component("faulty_motion_decomposer", "/faulty", "motion_decomposer",
                  inputs=["/faulty/sensors/core", "/faulty/jason/actions"], outputs=["/faulty/commands/velocity"]),
    ]
    text = architecture_yaml("team", components)
    assert "faulty_motion_decomposer: {pub: [faulty_commands_velocity], sub: [faulty_sensors_core]}" in text
    assert topic_atom("/faulty/jason/actions") == "faulty_jason_actions"      # published by nobody watched: left out
    pipeline = Pipeline(load_architecture(YamlSource("<discovered>", text)))
    try:
        pipeline.observe([Observation(f"resource({c.name})", True, 1.0, source="learned") for c in components])
        update = pipeline.observe([Observation("resource(faulty_motion_decomposer)", False, 2.0, 40.0, source="learned")])
        assert update.diagnoses == (("faulty_motion_decomposer",),)
    finally:
        pipeline.close()


def test_a_nodes_process_is_found_in_its_own_domain_and_never_guessed():
    import subprocess
    import sys

    import pytest

    from detection.learned.observer import node_processes

    # domains 201..203: valid ids outside the 1..100 that the ROS tests run real kobuki_sim nodes in
    # (tests/ros_domain.py), which a test running at the same time on another worker would add here
    sleepers = [subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)", "robot_bridge.ros2.kobuki_sim",
                                  "--robot", "faulty", "--domain-id", str(domain)]) for domain in (201, 202)]
    try:
        component = Component("faulty_kobuki_sim", "/faulty", "kobuki_sim")
        assert node_processes([component], 202)["faulty_kobuki_sim"].pid == sleepers[1].pid
        assert node_processes([component], 203) == {}
        with pytest.raises(ValueError, match="several processes look like the same node"):
            node_processes([component])                    # two teams, no domain: ambiguous
    finally:
        for sleeper in sleepers:
            sleeper.kill()
            sleeper.wait()
