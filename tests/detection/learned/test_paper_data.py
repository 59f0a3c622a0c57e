"""The `paper` data set kept in the repository is what the issue asks and what docs/perfbugs.md's Table I
was computed on: the ROS 2 nodes of the team *and their agents over Zenoh*, >= 10 fault-free and >= 20
faulty runs of >= 4 min, every kind three times (once of them in an agent's process), every run with
every node and both agents as components (runs once recorded without some were the defect
`settled_graph` fixed), the agents with their Zenoh keys, a file per run, <= 30 MB."""
from __future__ import annotations

import json
from collections import Counter

import numpy as np

from detection.learned.scenario import KINDS, PROFILES
from experiments.perfbugs import data_dir


def _manifest() -> dict:
    return json.loads((data_dir("paper") / "manifest.json").read_text())


def test_the_paper_data_set_is_complete_and_small_enough():
    folder = data_dir("paper")
    runs = _manifest()["runs"]
    faulty = [r for r in runs if r["faults"]]
    assert len(runs) - len(faulty) >= 10 and len(faulty) >= 20
    assert all(r["duration_s"] >= 240 for r in runs)
    assert Counter(r["faults"][0]["kind"] for r in faulty) == {k: 3 for k in KINDS}
    every_node = set(runs[0]["components"])
    assert len(every_node) == 12 and PROFILES["paper"].camera
    assert [r["id"] for r in runs if set(r["components"]) != every_node] == []
    assert all((folder / r["file"]).is_file() for r in runs)
    assert sum(p.stat().st_size for p in folder.iterdir()) <= 30 * 1024 * 1024


def test_the_paper_data_set_has_the_agents_as_components_with_bugs_of_every_kind():
    manifest = _manifest()
    assert manifest["agents"] is True
    runs = manifest["runs"]
    in_agents = [r["faults"][0] for r in runs if r["faults"] and r["faults"][0]["component"].endswith("_agent")]
    assert sorted(f["kind"] for f in in_agents) == sorted(KINDS)
    for run in runs:
        assert run["agents"]["agents"] == ["faulty", "helper"] and run["agents"]["silent"] == [], run["id"]
        for agent in ("faulty_agent", "helper_agent"):
            spec = run["components"][agent]
            keys = [c for c in [*spec["inputs"], *spec["outputs"]] if not c.startswith("/")]
            assert keys and sum(run["channels"][k]["events"] for k in keys) > 0, (run["id"], agent)

    # three runs lost faulty_agent's process mid-run (an interpreter defect, fixed since: test_stdlib's
    # test_an_event_after_a_wait_timed_out_resumes_nothing); its counters after that are missing (NaN),
    # never zeros, and no bug was injected into it there. Nothing else was lost.
    lost = {r["id"]: r["lost_processes"] for r in runs if r["lost_processes"]}
    assert set(map(tuple, lost.values())) <= {("faulty_agent",)} and len(lost) <= 3, lost
    for run in runs:
        if run["id"] in lost:
            assert all(f["component"] != "faulty_agent" for f in run["faults"])
            with np.load(data_dir("paper") / run["file"]) as arrays:
                counters = arrays["counters/faulty_agent"]
            gone = np.isnan(counters).all(axis=1)
            assert gone.any() and gone[np.argmax(gone):].all() and (counters[~gone][:, 1] > 0).all()
