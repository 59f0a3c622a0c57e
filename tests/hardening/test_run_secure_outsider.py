"""Issue 22: a real outsider process against a ``faultmas run --secure`` pair (the run's own code path:
``run_agent_processes(..., secure=True)`` on the embedded simulator, agents in processes of their own).

The outsider (tests/hardening/run_outsider.py) reads the MAS name and the hub's endpoint as anyone on the
host could, has a key of its own, and tries tell, achieve, tellHow and askOne against both robots, stops,
and ``.progress`` reports that claim a wrong diagnosis for the faulty robot. Every attempt is refused with a
log line (the robots' in their stderr, the run's hub in its ``dropped`` counters), and the run still ends
with its correct diagnosis. Before ``.progress`` was signed, the forged report ended the run ``wrong``.

The robots' keys too (the environment, here the run's hub, signs percepts, action results and the clock; an
agent signs its robot's actions): the outsider's percepts (overloaded motors, a pressed bumper), its clock far
ahead, its answer failing the faulty robot's first action and its turns for both robots are refused where they
arrive. Before they were signed, the same run ended ``wrong``: see docs/reliability.md, "Identity"."""
from __future__ import annotations

import io
import os
import queue
import re
import subprocess
import sys
import threading
from collections import Counter
from pathlib import Path

from agents.cooperative import RunResult, build_world, paper_scenario, run_agent_processes, PROCESS_BUSY_CAP
from agents.transport.identity import generate_keys

REPO = Path(__file__).resolve().parents[2]


def _lines(stream, into: queue.Queue) -> None:
    for line in stream:
        into.put(line)


def test_an_outsider_can_neither_message_stop_nor_forge_progress_robots_minds_pauses_or_subscriptions(tmp_path):
    from robot_bridge.sim.server import SimServer

    generate_keys(tmp_path, ["mallory"])
    scenario = paper_scenario("encoders", seed=3)
    world, bridges = build_world(scenario, busy_cap=PROCESS_BUSY_CAP)
    robots = [r.name for r in scenario.robots]
    hubs, outsiders = [], []
    said: queue.Queue = queue.Queue()

    teams = []

    def serve(hub):
        """Start the simulator's server and the run's inspector (as ``--inspect`` does), then the outsider,
        connected before the robots start."""
        from agents.inspector.hub import TeamHub

        hubs.append(hub)
        stop_sim = SimServer(hub.session, scenario.mas, bridges, sealed=hub.sealed_channel()).start().stop
        teams.append(TeamHub(hub.session, scenario.mas, transport=hub).start())
        outsider = subprocess.Popen(
            [sys.executable, "-m", "tests.hardening.run_outsider", "--mas", scenario.mas, "--connect",
             hub.endpoints[0], "--key", str(tmp_path / "mallory.key"), "--robots", ",".join(robots),
             "--faulty", "faulty", "--wrong", "wheels"],
            cwd=REPO, env=dict(os.environ, PYTHONPATH=str(REPO), PYTHONUNBUFFERED="1"),
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        outsiders.append(outsider)
        threading.Thread(target=_lines, args=(outsider.stdout, said), daemon=True).start()
        assert said.get(timeout=60).strip() == "READY", outsider.stderr.read()[-2000:]
        return lambda: (teams[0].close(), stop_sim())

    err = io.StringIO()
    try:
        # --allow-pause: the agents obey pause and step, from the project's keys only
        log = run_agent_processes(scenario, ["--bridge", "zenoh", "--allow-pause"], 180.0, world=world, err=err,
                                  serve=serve, secure=True)
        try:
            outsiders[0].wait(timeout=60)   # it has sent everything (or failed) by now
        except subprocess.TimeoutExpired:
            outsiders[0].kill()
            raise AssertionError(f"the outsider hung: {outsiders[0].stderr.read()[-3000:]}\n{err.getvalue()[-3000:]}") from None
    finally:
        for bridge in bridges.values():
            bridge.shutdown()
        for outsider in outsiders:
            outsider.kill()
    result = RunResult(scenario, log.results(), log.marks, log.done.is_set(), world, list(log.died),
                       list(log.frozen))
    logged = err.getvalue()
    assert result.outcome == "correct", (result.outcome, [r.diagnosis for r in result.robots], logged[-3000:])
    assert said.get(timeout=5).strip() == "SENT", outsiders[0].stderr.read()[-2000:]
    assert result.robots[0].diagnosis == "encoders"
    # the run's hub: the stops and the forged progress reports on the control key
    # the run's hub (its control key, the simulator it serves, its inspector, its directory): one line and one
    # count per refused message
    assert dict(hubs[0].dropped) == {
        "not_a_member": 2,      # an unsigned stop naming a member (a mere claim), the 'launcher' without its token
        # the outsider's own signed stop and progress report; its own subscription token
        "unknown_sender": 2 + 1,
        # a progress report naming the faulty robot; a turn for each robot (the simulator); the forged mind (the
        # inspector); the directory query saying the helper subscribes, the helper's token no heartbeat lists
        "unsigned": 1 + 2 + 1 + 1 + 1,
        # the same, signed with the outsider's key as the faulty robot, as each robot, as the faulty robot, as
        # the helper
        "bad_signature": 1 + 2 + 1 + 1,
    }, logged[-3000:]
    # each robot's process: one log line per refused message, by key and reason (the drop log's format)
    refused = Counter((_kind(m.group(1)), m.group(2)) for m in re.finditer(
        r"dropped message on (.+?) from [^:\n]+: ([a-z_]+)", logged))
    messages = {"unsigned": 2, "unknown_sender": 4 + 2, "bad_signature": 1 + 1, "not_a_member": 2}
    expected = Counter({("messages", reason): n * len(robots) for reason, n in messages.items()})
    expected.update({("robot/faulty/percepts", "unsigned"): 1, ("robot/faulty/percepts", "bad_signature"): 1,
                     ("robot/faulty/percepts", "replayed"): 1,       # the helper's snapshot put on its key
                     ("robot/faulty/status", "unsigned"): 1, ("robot/faulty/status", "bad_signature"): 1,
                     ("clock", "unsigned"): len(robots),
                     ("inspect/faulty", "unsigned"): 1, ("inspect/faulty", "bad_signature"): 1,  # pause, step
                     ("df", "unsigned"): len(robots), ("df", "bad_signature"): len(robots),
                     ("subscribes/mallory", "unknown_sender"): len(robots),
                     ("subscribes/helper", "unsigned"): 1})     # the faulty robot's process (the helper's own)
    assert refused == expected, logged[-3000:]
    assert "evil" not in "".join(str(m) for m in result.marks)
    shown = teams[0].view()["team"]
    assert {entry["agent"] for entry in shown} == set(robots) and all(e.get("cycles") != 424242 for e in shown)


def _kind(where: str) -> str:
    """What a drop's key is, for counting: a robot's channel, the clock, an agent's inspector key, the directory,
    a subscription token's agent; ``messages`` for inboxes and the control key."""
    parts = where.split("/")
    if where.startswith("faultmas/coop/") and parts[2] in ("robot", "inspect", "subscribes", "clock", "df"):
        return "/".join(parts[2:5] if parts[2] == "robot" else parts[2:4] if parts[2] in ("inspect", "subscribes")
                        else parts[2:3])
    return "messages"
