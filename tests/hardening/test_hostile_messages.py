"""Issue 22, found items 1, 4 and 5 on the network boundary: one hostile message must be dropped with a
reason, and the agent must go on (a valid tell after it still arrives). Each payload runs in a child
process (``hostile_inbox``), once with the compiled interpreter when it is built (where deep recursion
used to overflow the C stack: SIGSEGV, no log line) and once run from source (RecursionError)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.hardening.payloads import HOSTILE

REPO = Path(__file__).resolve().parents[2]
EXPECTED_REASON = {"deep_json": "not_json", "bad_batch": "missing_field"}


def run_child(names: list[str], pure: bool) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(REPO))
    env.pop("FAULTMAS_PURE_PYTHON", None)
    if pure:
        env["FAULTMAS_PURE_PYTHON"] = "1"
    return subprocess.run([sys.executable, "-m", "tests.hardening.hostile_inbox", *names], cwd=REPO, env=env,
                          capture_output=True, text=True, timeout=120)


def outcome(child: subprocess.CompletedProcess) -> tuple[dict, list]:
    report = json.loads(child.stdout.strip().splitlines()[-1].split(" ", 1)[1])
    return report["dropped"], report["beliefs"]


@pytest.mark.parametrize("pure", [False, True], ids=["compiled-if-built", "from-source"])
def test_each_hostile_message_is_dropped_with_a_reason_and_the_agent_goes_on(pure):
    names = sorted(set(HOSTILE) - {"bad_batch"})
    child = run_child(names, pure)
    assert child.returncode == 0, f"agent died (exit {child.returncode}): {child.stderr[-2000:]}"
    dropped, beliefs = outcome(child)
    assert dropped == {name: {EXPECTED_REASON.get(name, "unparsable_content"): 1} for name in names}
    assert "ok[source(alice)]" in beliefs  # the valid tell after them arrived
    reasons = [line for line in child.stderr.splitlines() if "dropped message" in line]
    assert len(reasons) == len(names) and all("bob" in line for line in reasons)  # one line each


def test_a_batch_of_21000_bad_envelopes_writes_a_bounded_log_that_counts_every_one():
    child = run_child(["bad_batch"], pure=False)
    assert child.returncode == 0, child.stderr[-2000:]
    dropped, beliefs = outcome(child)
    assert dropped == {"bad_batch": {"missing_field": 21_000}}
    assert "ok[source(alice)]" in beliefs
    lines = child.stderr.splitlines()
    assert len(lines) <= 20, f"{len(lines)} log lines for one flood"
    logged_one_by_one = sum("dropped message on" in line for line in lines)
    summed_up = [line for line in lines if "more messages for missing_field" in line]
    assert summed_up, "the suppressed drops must be summed up, not lost"
    counted = sum(int(line.split("dropped ", 1)[1].split(" ", 1)[0]) for line in summed_up)
    assert logged_one_by_one + counted == 21_000  # nothing dropped silently
