"""Issue 22, identity: in the secure profile a liveliness token is a claim anyone on the network can make, so
presence needs a signed proof (``agents.transport.proved_presence``), and the inspector's timeline shows only
``.progress`` reports signed by the agent they name.

A real outsider process (its own Zenoh session and key) declares tokens on a member's name (bob) and on a name
that is no member (ghost), puts heartbeats that prove nothing and forged ``.progress`` reports. What a launcher
or a viewer sees (the run's hub transport and the inspector's ``TeamHub`` on it): neither ghost nor bob alive
before bob starts; bob alive once his process runs; bob gone within the lease after a SIGKILL, though the
outsider's token on his name is still up (Zenoh reports a key gone only with its last token); no forged report
in the timeline, bob's own reports in it. The same on the page of ``faultmas inspect --project`` (another
process, keys from the project). Before: ghost and bob were listed alive from the outsider's tokens
and bob stayed alive after his death; the forged reports were on the timeline."""
from __future__ import annotations

import json
import os
import queue
import re
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

from agents.inspector.hub import TeamHub
from agents.transport import ZenohOptions, ZenohTransport, loopback_endpoint
from agents.transport.identity import generate_keys, project_identity
from agents.transport.proved_presence import LEASE, ProvedPresence
from agentspeak.mas2j import load_mas2j
from tests.agents.transport_fixtures import unique_mas

REPO = Path(__file__).resolve().parents[2]
BOB = "!start.\n+!start <- .progress(started, hello); .wait(500); !start.\n"


def _until(condition, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.1)
    return condition()


def _env() -> dict:
    return dict(os.environ, PYTHONPATH=str(REPO), PYTHONUNBUFFERED="1")


def test_an_outsiders_tokens_and_reports_neither_make_anyone_alive_nor_reach_the_timeline(tmp_path):
    mas, endpoint = unique_mas(), loopback_endpoint()
    generate_keys(tmp_path / "keys", ["alice", "bob"])
    generate_keys(tmp_path / "outside", ["mallory"])
    (tmp_path / "bob.asl").write_text(BOB)
    (tmp_path / "alice.asl").write_text("")
    project_file = tmp_path / "team.mas2j"
    project_file.write_text(f'MAS {mas} {{ agents: alice alice.asl [key="keys"]; bob bob.asl [key="keys"]; }}\n')
    identity = project_identity(load_mas2j(str(project_file)))      # the public keys only: a launcher's
    outsider = bob = page = None
    with ZenohTransport(mas, ZenohOptions(listen=(endpoint,)), identity=identity) as hub:
        team = TeamHub(hub.session, mas, transport=hub).start()
        try:
            outsider = subprocess.Popen(
                [sys.executable, "-m", "tests.hardening.presence_outsider", "--mas", mas, "--connect", endpoint,
                 "--key", str(tmp_path / "outside" / "mallory.key"), "--names", "bob,ghost", "--progress-as", "bob"],
                cwd=REPO, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            said: queue.Queue = queue.Queue()
            threading.Thread(target=lambda: [said.put(line) for line in outsider.stdout], daemon=True).start()
            page = subprocess.Popen([sys.executable, "-m", "agents", "inspect", "--project", str(project_file),
                                     "--connect", endpoint, "--listen", "127.0.0.1:0"],
                                    cwd=tmp_path, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            url = re.search(r"at (http://\S+/) ", page.stdout.readline()).group(1)
            assert said.get(timeout=60).strip() == "READY", outsider.stderr.read()[-2000:]
            time.sleep(3.0)   # tokens, forged heartbeats (every 0.5 s) and reports have all arrived by now
            assert hub.alive_agents() == frozenset(), "an outsider's token made someone alive"
            assert not any(entry["alive"] for entry in team.agents.values()), team.agents
            assert team.timeline == [] and team.refused_marks == 1, (team.timeline, team.refused_marks)

            bob = subprocess.Popen([sys.executable, "-m", "agents", "agent", "run", "bob.asl", "--name", "bob",
                                    "--mas", mas, "--project", str(project_file), "--connect", endpoint],
                                   cwd=tmp_path, env=_env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                   text=True)
            assert _until(lambda: "bob" in hub.alive_agents(), 60), "bob's own heartbeats did not prove him"
            assert _until(lambda: team.agents.get("bob", {}).get("alive"), 10), team.agents
            assert _until(lambda: any(m["agent"] == "bob" and m["step"] == "started" for m in team.timeline), 30)

            bob.kill()
            bob.wait(30)
            killed = time.monotonic()
            assert _until(lambda: "bob" not in hub.alive_agents(), LEASE + 15), \
                "bob, dead, still alive: the outsider's token kept him up"
            print(f"bob gone {time.monotonic() - killed:.1f} s after his SIGKILL (lease {LEASE:g} s)")
            assert not team.agents["bob"]["alive"]
            assert "ghost" not in hub.alive_agents() and not team.agents.get("ghost", {}).get("alive")
            assert outsider.poll() is None, "the outsider ended early: its token on bob was not up all along"
            assert not any(m["detail"] == "evil" for m in team.timeline), team.timeline
            # the page of `faultmas inspect --project`: the same verdicts
            def shown_alive() -> list[str]:
                team_shown = json.load(urllib.request.urlopen(url + "api/team", timeout=10))["team"]
                return [a["agent"] for a in team_shown if a["alive"]]
            assert _until(lambda: shown_alive() == [], 15), shown_alive()   # its own lease, a moment later
            marks = json.load(urllib.request.urlopen(url + "api/timeline.json", timeout=10))["marks"]
            assert any(m["agent"] == "bob" and m["step"] == "started" for m in marks), marks
            assert not any(m["detail"] == "evil" for m in marks), marks
        finally:
            team.close()
            for proc in (outsider, bob, page):
                if proc is not None and proc.poll() is None:
                    proc.kill()
                    proc.wait(30)
    reasons = dict(hub.dropped)
    assert reasons.get("unsigned", 0) >= 2 and reasons.get("bad_signature", 0) >= 2, reasons   # the heartbeats


def test_proved_presence_needs_a_token_and_a_proof_within_the_lease():
    now = [0.0]
    seen: dict[str, bool] = {}
    presence = ProvedPresence(lambda agent, alive: seen.__setitem__(agent, alive), lease=10.0, clock=lambda: now[0])
    presence.token("bob", True)
    assert seen == {"bob": False}                      # a token alone: a claim
    presence.proved("carol")
    assert seen["carol"] is False                      # a proof without a token: not up (gone, or not yet)
    presence.proved("bob")
    assert seen["bob"] is True
    now[0] = 9.0
    presence.expire()
    assert seen["bob"] is True
    now[0] = 10.5
    presence.expire()
    assert seen["bob"] is False                        # no proof for longer than the lease: gone, token or not
    presence.proved("bob")
    assert seen["bob"] is True
    presence.token("bob", False)
    assert seen["bob"] is False                        # the token withdrawn: gone at once
    now[0] = 30.0
    presence.expire()
    assert presence._proved_at == {}                   # forgotten: bounded
