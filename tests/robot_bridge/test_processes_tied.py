"""A child that faultmas starts never outlives its parent (``robot_bridge.processes.spawn``/``die_with_parent``),
however the parent ends: real processes, the parent killed with SIGKILL (no clean-up of its own can run)."""
from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

REPO = Path(__file__).resolve().parents[2]

# A parent that starts two tied children (from its main thread, or from a thread that ends at once), one of them
# frozen (SIGSTOP) if asked, prints their pids and waits to be killed.
PARENT = """
import os, signal, sys, threading, time
from robot_bridge.processes import spawn
CHILD = [sys.executable, "-c", "from robot_bridge.processes import die_with_parent; import time; "
         "die_with_parent(); print('ready', flush=True); time.sleep(120)"]
how = sys.argv[1]
children = []
def start():
    for _ in range(2):
        children.append(spawn(CHILD, stdout=None, start_new_session=True))
if how == "thread":
    worker = threading.Thread(target=start)
    worker.start()
    worker.join()          # the thread that forked is gone: its children must live on
else:
    start()
time.sleep(1.0)
if how == "frozen":
    os.kill(children[0].pid, signal.SIGSTOP)
print(" ".join(str(c.pid) for c in children), flush=True)
time.sleep(120)
"""


def _alive(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def _gone_within(pids: list[int], seconds: float) -> list[int]:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline and any(_alive(pid) for pid in pids):
        time.sleep(0.1)
    return [pid for pid in pids if _alive(pid)]


@pytest.mark.parametrize("how", ["main", "thread", "frozen"])
def test_children_die_with_a_parent_killed_by_sigkill(how):
    env = dict(os.environ, PYTHONPATH=str(REPO))
    parent = subprocess.Popen([sys.executable, "-c", PARENT, how], cwd=REPO, env=env, text=True,
                              stdout=subprocess.PIPE)
    try:
        line = ""
        while not line.strip() or line.startswith("ready"):
            line = parent.stdout.readline()
            assert line, "the parent ended before it started its children"
        pids = [int(pid) for pid in line.split()]
        time.sleep(1.5)
        assert all(_alive(pid) for pid in pids), "a child died while its parent lived (a thread that forked ended)"
        parent.kill()
        parent.wait()
        # PDEATHSIG: at once; the lifeline (children of a thread): SIGTERM, then SIGKILL 3 s later at most
        assert _gone_within(pids, 10.0) == [], f"children of a SIGKILLed parent ({how}) still alive"
    finally:
        if parent.poll() is None:
            parent.kill()
        for child in psutil.Process().children(recursive=True):
            child.kill()


def test_a_process_not_started_by_spawn_is_left_alone():
    from robot_bridge.processes import PARENT_ENV, die_with_parent

    assert PARENT_ENV not in os.environ
    assert die_with_parent() is False


def test_the_parent_variable_is_not_inherited_by_the_childs_own_children():
    """A faultmas process started by a faultmas process starts processes of its own (``faultmas run`` from an
    agent's ``.system``): theirs must not take its parent for theirs (they would end at once)."""
    code = ("import os; from robot_bridge.processes import die_with_parent, PARENT_ENV; "
            "print(die_with_parent(), PARENT_ENV in os.environ)")
    from robot_bridge.processes import spawn

    child = spawn([sys.executable, "-c", code], cwd=REPO, env=dict(os.environ, PYTHONPATH=str(REPO)),
                  stdout=subprocess.PIPE, text=True)
    out, _ = child.communicate(timeout=60)
    assert out.split() == ["True", "False"]
