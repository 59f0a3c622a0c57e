"""A short real run with the agents (``faultmas experiment perfbugs --generate --agents``): the ROS 2 team,
the workload, and Faulty's and Helper's AgentSpeak agents in their own processes over Zenoh. The
recorder must make each agent a component, with its process's counters, its ROS 2 bridge topics and the
Zenoh keys it sends and receives on, and leave the ROS 2 channels' columns as in runs without agents."""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="ROS 2 is an optional extra (pip install 'faultmas[ros2]')")

DOMAIN = 1 + (os.getpid() + 37) % 100


@pytest.fixture(scope="module")
def agents_run(tmp_path_factory):
    from detection.learned.scenario import Profile, record_run
    from experiments.perfbugs_agents import CooperativeAgents

    out = tmp_path_factory.mktemp("agents-run")
    profile = Profile("agents-test", fault_free_runs=1, faulty_runs=0, duration_s=20.0, camera=False,
                      fault_length_s=(5.0, 10.0))
    entry = record_run({"id": 0, "seed": 3, "kind": None}, profile, out, lambda text: None,
                       agents=CooperativeAgents(), domain_id=DOMAIN)
    manifest = {"format": 1, "profile": {"name": profile.name}, "agents": True, "runs": [entry]}
    (out / "manifest.json").write_text(json.dumps(manifest))
    return out, entry


@pytest.mark.timeout(240)
def test_the_agents_are_components_with_their_processes_topics_and_zenoh_keys(agents_run):
    out, entry = agents_run
    for agent in ("faulty", "helper"):
        spec = entry["components"][f"{agent}_agent"]
        channels = set(spec["inputs"]) | set(spec["outputs"])
        keys = {c for c in channels if not c.startswith("/")}
        assert f"/{agent}/jason/actions" in spec["outputs"], spec            # its ROS 2 bridge node
        assert "faultmas/coop/control" in spec["outputs"], spec              # its progress reports ("agent": A)
        for key in keys:
            assert entry["channels"][key]["type"] == "zenoh/json"
            assert entry["channels"][key]["columns"][0] == "size"
        assert sum(entry["channels"][k]["events"] for k in keys) > 0
    control = entry["channels"]["faultmas/coop/control"]["columns"]
    assert {"agent#len", "command#len", "step#len"} <= set(control)        # generic: the JSON's own fields
    with np.load(out / entry["file"]) as arrays:
        counters = arrays["counters/faulty_agent"]
        assert counters.shape[1] == 8 and len(counters) >= 15 and np.isfinite(counters).all()
        assert counters[-1, 0] > counters[0, 0]                 # the agent's process did use CPU
        assert len(arrays["events/faultmas/coop/control/x"]) > 0


def test_ros_channels_keep_the_columns_of_runs_without_agents(agents_run):
    from experiments.perfbugs import data_dir

    _, entry = agents_run
    smoke = json.loads((data_dir("smoke") / "manifest.json").read_text())["runs"][0]["channels"]
    ros = {t: spec for t, spec in entry["channels"].items() if t.startswith("/") and t in smoke}
    assert "/faulty/odom" in ros
    for topic, spec in ros.items():
        assert spec["columns"] == smoke[topic]["columns"], topic


def test_the_run_loads_as_a_data_set_with_agent_features(agents_run):
    from detection.learned.dataset import load

    out, _ = agents_run
    dataset = load(out)
    samples = dataset.components["helper_agent"]
    assert any(name.startswith("faultmas/coop/") for name in samples.features)
    assert any(name.startswith("/helper/") for name in samples.features)
    assert samples.X.shape == (len(samples.Y), len(samples.features)) and len(samples.Y) >= 15
