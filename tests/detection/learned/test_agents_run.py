"""A short real run with the agents (``faultmas experiment perfbugs --generate --agents``): the ROS 2 team,
the workload, and Faulty's and Helper's AgentSpeak agents in their own processes over Zenoh, with a memory
leak injected into Helper's agent process for part of the run. The recorder must make each agent a
component, with its process's counters, its ROS 2 bridge topics and the Zenoh keys it sends and receives
on, and leave the ROS 2 channels' columns as in runs without agents; the leak must show in that agent's
process only, and only while the ground truth says it is on."""
from __future__ import annotations

import json
import time

import numpy as np
import pytest

from tests.ros_domain import ros_domain

pytest.importorskip("rclpy", reason="ROS 2 is an optional extra (pip install 'faultmas[ros2]')")

DOMAIN = ros_domain(37)


@pytest.fixture(scope="module")
def agents_run(tmp_path_factory):
    from detection.learned.scenario import Profile, record_run
    from experiments.perfbugs_agents import CooperativeAgents

    out = tmp_path_factory.mktemp("agents-run")
    profile = Profile("agents-test", fault_free_runs=0, faulty_runs=1, duration_s=20.0, camera=False,
                      fault_length_s=(6.0, 8.0))              # the leak: from 8-9 s for 6-8 s
    entry = record_run({"id": 100, "seed": 3, "kind": "memory_leak", "component": "helper_agent"}, profile, out,
                       lambda text: None, agents=CooperativeAgents(), domain_id=DOMAIN)
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


def test_a_memory_leak_injected_into_an_agent_shows_in_its_process_only_while_on(agents_run):
    from detection.learned.counters import COUNTER_NAMES, targets_from_counters
    from robot_bridge.ros2.perfbugs import LEAK_BYTES_PER_S

    out, entry = agents_run
    [bug] = entry["faults"]
    assert (bug["component"], bug["kind"]) == ("helper_agent", "memory_leak")
    rss = COUNTER_NAMES.index("rss_mb")
    with np.load(out / entry["file"]) as arrays:
        ticks = arrays["ticks"][1:]
        on = (ticks >= bug["start"] + 1.0) & (ticks < bug["end"])            # whole seconds of the leak
        off = (ticks < bug["start"]) | (ticks >= bug["end"] + 1.0)
        growth = {a: targets_from_counters(arrays[f"counters/{a}_agent"])[:, rss] for a in ("faulty", "helper")}
    leak_mb = LEAK_BYTES_PER_S / 2**20
    assert on.sum() >= 4 and off.sum() >= 6
    assert np.median(growth["helper"][on]) > 0.7 * leak_mb, growth["helper"]       # 2 MiB/s while on
    assert np.median(growth["helper"][off]) < 0.1 * leak_mb, growth["helper"]      # given back, then quiet
    assert np.median(growth["faulty"][on]) < 0.1 * leak_mb, growth["faulty"]       # the other agent: untouched


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


@pytest.mark.slow     # ~25 s; make test keeps the live learned path in test_observe_learned.py (a node over ROS 2)
@pytest.mark.timeout(300)
def test_a_model_of_an_agent_watches_it_live_over_ros2_and_zenoh(agents_run, tmp_path):
    """The online path for an agent: its model's channels (bridge topics and Zenoh keys) fit the live
    agent, its process is found by its command line, its keys' samples reach the buffers through a Zenoh
    session shared with the observers' tap (``faultmas observe --zenoh --learned``: one session), and it is
    scored; then the same through the command. The model is the recorded run's feature layout with a
    neutral fit (no training needed to test the plumbing; detection quality is the data set's
    evaluation's job)."""
    import subprocess
    import sys

    import rclpy

    from detection.taps.zenoh import ZenohKeys
    from robot_bridge.ros2.runtime import loopback_env

    from detection.learned.counters import TARGET_NAMES
    from detection.learned.dataset import load
    from detection.learned.model import ComponentModel
    from detection.learned.scenario import ROBOTS, Workload
    from detection.learned.watch import LiveLearnedObserver
    from experiments.perfbugs_agents import CooperativeAgents
    from robot_bridge.ros2.launch import Supervisor, plan
    from robot_bridge.ros2.runtime import RosContext

    out, _ = agents_run
    features = load(out).components["faulty_agent"].features
    d, k = len(features), len(TARGET_NAMES)
    model = ComponentModel("faulty_agent", features, list(TARGET_NAMES), np.zeros(d), np.ones(d), np.zeros(k),
                           np.ones(k), np.zeros((k, d)), np.zeros(k), np.zeros(k), np.eye(k), threshold=1e12,
                           target_fpr=0.005)
    domain = ros_domain(41)
    agents = CooperativeAgents()
    supervisor = Supervisor(plan(list(ROBOTS), fault=agents.robot_fault(3), camera=False, seed=3), domain)
    supervisor.start()
    team = live = keys = None
    emitted: list = []
    model.save(tmp_path / "faulty_agent.npz")
    try:
        assert supervisor.wait_ready(90) == set()
        team = agents.start(domain, 3)
        with RosContext(domain_id=domain) as work:
            Workload(work.add(rclpy.create_node("perfbugs_workload", context=work.context)), ROBOTS, seed=3)
            time.sleep(3.0)
            keys = ZenohKeys(connect=[team.endpoint])          # the observers' Zenoh tap's session
            live = LiveLearnedObserver({"faulty_agent": model}, [f"/{r}" for r in ROBOTS], emitted.extend, domain,
                                       zenoh_connect=[team.endpoint], zenoh_keys=keys)
            assert live.zenoh.tap.keys is keys
            assert live.observer.processes["faulty_agent"].pid == team.pids["faulty"]
            agent_channels = [t for t in live.observer.buffers if not t.startswith("/")]
            assert "faultmas/coop/agent/faulty/inbox" in agent_channels
            drained = []
            drain = live.zenoh.drain
            live.zenoh.drain = lambda: drained.append(drain()) or drained[-1]
            deadline = time.monotonic() + 60
            while (not emitted or sum(drained) == 0) and time.monotonic() < deadline:
                time.sleep(0.5)
            live.close()
            live = None
            command = subprocess.run([sys.executable, "-m", "agents", "observe", "--zenoh", "--learned", str(tmp_path),
                                      "--connect", team.endpoint, "--domain-id", str(domain), "--json",
                                      "--duration", "8"], text=True, capture_output=True, timeout=120,
                                     env=loopback_env())
    finally:
        if live is not None:
            live.close()
        if keys is not None:
            keys.close()
        if team is not None:
            team.stop()
        supervisor.stop()
    assert sum(drained) > 0, "no Zenoh sample of the agents reached the observer"
    assert [o.literal for o in emitted][:1] == ["resource(faulty_agent)"]
    assert emitted[0].source == "learned" and np.isfinite(emitted[0].measured)
    assert command.returncode == 0, command.stderr[-2000:]
    assert "learned resource observer watching faulty_agent" in command.stderr
    first = json.loads(command.stdout.splitlines()[0])
    assert [(c["literal"], c["source"]) for c in first["changed"]] == [("resource(faulty_agent)", "learned")]
