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
