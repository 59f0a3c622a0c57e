"""What ``faultmas experiment perfbugs --generate [--agents] [--jobs N]`` records, without recording: the
plan of runs (with the agents every kind once in an agent's process, the robots' runs as without them),
the order (fault-free and faulty mixed, so a generation cut short leaves both), and the ROS domains
that runs recorded at once hold (never shared)."""
from __future__ import annotations

import subprocess
import sys
from collections import Counter

from detection.learned import scenario
from detection.learned.scenario import KINDS, PROFILES, allocate_domain, run_plan


def test_with_the_agents_every_kind_is_once_in_an_agent_and_the_other_runs_are_unchanged():
    without, with_agents = run_plan(PROFILES["paper"]), run_plan(PROFILES["paper"], agents=True)
    faulty = [r for r in with_agents if r["kind"]]
    in_agents = [r for r in faulty if r["component"].endswith("_agent")]
    assert sorted(r["kind"] for r in in_agents) == sorted(KINDS)
    assert {r["component"] for r in in_agents} == {"faulty_agent", "helper_agent"}
    assert Counter(r["kind"] for r in faulty) == {k: 3 for k in KINDS}
    assert [r for r in with_agents if r not in in_agents] == [r for r in without if r["id"] not in
                                                              {a["id"] for a in in_agents}]


def test_runs_are_recorded_fault_free_and_faulty_mixed():
    order = scenario._interleaved(run_plan(PROFILES["paper"], agents=True))
    first_half = order[:len(order) // 2]
    assert sum(1 for r in first_half if not r["kind"]) in (5, 6, 7)        # 12 of 33 are fault-free
    assert sorted(r["id"] for r in order) == sorted(r["id"] for r in run_plan(PROFILES["paper"]))


def test_runs_recorded_at_once_never_share_a_ros_domain(tmp_path, monkeypatch):
    monkeypatch.setattr(scenario, "LOCKS", tmp_path)
    first, first_lock = allocate_domain(7)
    second, second_lock = allocate_domain(7)
    assert first != second and {first, second} <= set(scenario.DOMAINS)
    # another process sees both taken (flock is per open file, so this is what two workers see)
    probe = ("import fcntl, sys; from pathlib import Path\n"
             f"d = Path({str(tmp_path)!r})\n"
             "for dom in sys.argv[1:]:\n"
             "    f = open(d / f'faultmas-perfbugs-domain-{dom}.lock', 'w')\n"
             "    try: fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB); print('free')\n"
             "    except OSError: print('taken')\n")
    taken = subprocess.run([sys.executable, "-c", probe, str(first), str(second)], capture_output=True, text=True)
    assert taken.stdout.split() == ["taken", "taken"]
    first_lock.close()
    again, again_lock = allocate_domain(7)
    assert again == first                          # given back at the end of its run
    second_lock.close(), again_lock.close()


def test_jobs_and_agents_need_generate():
    for option in (["--agents"], ["--jobs", "2"]):
        done = subprocess.run([sys.executable, "-m", "agents", "experiment", "perfbugs", *option],
                              capture_output=True, text=True)
        assert done.returncode == 2 and "go with --generate" in done.stderr, done.stderr
