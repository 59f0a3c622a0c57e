"""Issue 22, found item 2, default profile: with a real Zenoh session and a real outsider process, plans
and goals from strangers or under a forged name (the receiver's own) are refused with a reason, an
envelope with ``from`` twice is refused, a stranger's stop does not stop the MAS; a stranger may still
tell, and a member's goal still runs."""
from __future__ import annotations

import os
import subprocess
import sys
import threading
from pathlib import Path

from agents.transport import ZenohOptions, ZenohTransport, loopback_endpoint
from agents.zenoh_arch import TransportBridge
from agentspeak.runtime import LocalRuntime
from tests.agents.transport_fixtures import unique_mas

REPO = Path(__file__).resolve().parents[2]
BOB = "+!act[source(S)] <- +did(act, S).\n"


def test_an_outsider_process_cannot_plant_plans_goals_or_stop_the_mas():
    mas, endpoint = unique_mas(), loopback_endpoint()
    runtime = LocalRuntime(printer=lambda name, text: None)
    runtime.add_agent("bob", BOB)
    with ZenohTransport(mas, ZenohOptions(listen=(endpoint,))) as transport:
        bridge = TransportBridge(runtime, transport, declared=["alice", "bob"], members=["alice", "bob"]).attach()
        outsider = subprocess.Popen([sys.executable, "-m", "tests.hardening.outsider", "--mas", mas,
                                     "--connect", endpoint], cwd=REPO, env=dict(os.environ, PYTHONPATH=str(REPO)),
                                    stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        done = threading.Event()
        waiter = threading.Thread(target=lambda: (outsider.wait(), done.set()), daemon=True)
        waiter.start()
        why = None
        while not done.is_set():  # the MAS runs until the outsider has sent everything, then a little more
            why = bridge.run(timeout=0.5)
            assert why == "timeout", "the MAS stopped: an outsider's stop was obeyed"
        why = bridge.run(timeout=2.0)
        out, err = outsider.communicate()
        assert outsider.returncode == 0 and "SENT" in out, err[-2000:]
        bridge.detach()
    assert why == "timeout"
    beliefs = {str(b) for b in runtime.agents["bob"].bb.literals()}
    assert "did(act,alice)[source(self)]" in beliefs          # a member's goal runs
    assert "hello[source(mallory)]" in beliefs                # anyone may tell
    assert not any("evil" in b or "did(act,mallory)" in b or "did(act,bob)" in b for b in beliefs), beliefs
    assert not any("evil" in str(plan) for plan in runtime.agents["bob"].plans.plans), "a planted plan"
    # the stranger's plan is 'untrusted_code' (as before), its goal and both stops 'not_a_member'
    assert dict(transport.dropped) == {"forged_sender": 2, "untrusted_code": 1, "not_a_member": 1 + 2,
                                       "duplicate_field": 1}
