"""The `paper` data set kept in the repository is what the issue asks and what docs/perfbugs.md's Table I
was computed on: >= 10 fault-free and >= 20 faulty runs of >= 4 min, every kind three times, every run
with every node of the team (runs once recorded without some were the defect `settled_graph` fixed),
a file per run, <= 30 MB."""
from __future__ import annotations

import json
from collections import Counter

from detection.learned.scenario import KINDS, PROFILES
from experiments.perfbugs import data_dir


def test_the_paper_data_set_is_complete_and_small_enough():
    folder = data_dir("paper")
    manifest = json.loads((folder / "manifest.json").read_text())
    runs = manifest["runs"]
    faulty = [r for r in runs if r["faults"]]
    assert len(runs) - len(faulty) >= 10 and len(faulty) >= 20
    assert all(r["duration_s"] >= 240 for r in runs)
    assert Counter(r["faults"][0]["kind"] for r in faulty) == {k: 3 for k in KINDS}
    every_node = set(runs[0]["components"])
    assert len(every_node) == 10 and PROFILES["paper"].camera
    assert [r["id"] for r in runs if set(r["components"]) != every_node] == []
    assert all((folder / r["file"]).is_file() for r in runs)
    assert sum(p.stat().st_size for p in folder.iterdir()) <= 30 * 1024 * 1024
