"""The inspector without a browser: an agent's mind over a real Zenoh session, pause/step exactly one
reasoning cycle, the switch that refuses them, malformed state messages dropped with a log line, and
the command line's loopback rule. (The page itself: test_inspector_browser.py.)"""
from __future__ import annotations

import json
import logging
import threading

import pytest
import zenoh

from agents.inspector import TIMELINE_MARKS, keys
from agents.inspector.cli import parse_listen
from agents.inspector.hub import TeamHub
from agents.inspector.publisher import MindPublisher
from agents.transport import ZenohOptions, ZenohTransport, loopback_endpoint
from agents.transport.config import build_config
from agents.zenoh_arch import TransportBridge
from agentspeak.communication import Message
from agentspeak.runtime import LocalRuntime
from agentspeak.terms import Literal
from tests.agents.transport_fixtures import poll, unique_mas

# .wait(1): a busy loop that never leaves the compiled interpreter keeps Python's interpreter lock, so
# other threads (Zenoh's callbacks, the inspector's) wait for it; an agent of a robot waits on its robot.
COUNTER = """
count(0).
!loop.
+!loop : count(N) & N < 100000000 <- -+count(N + 1); !inner(N); .wait(1); !loop.
+!inner(N) <- true.
"""


class Team:
    """One busy agent in a runtime of its own thread, on a Zenoh transport, with its publisher; and a
    second Zenoh session that plays the inspector's."""

    def __init__(self, allow_control: bool) -> None:
        self.mas = unique_mas("insp")
        self.runtime = LocalRuntime()
        self.agent = self.runtime.add_agent("counter", COUNTER, "counter.asl")
        self.transport = ZenohTransport(self.mas, ZenohOptions(listen=(loopback_endpoint(),))).open()
        self.bridge = TransportBridge(self.runtime, self.transport, declared=["counter"]).attach()
        self.publisher = MindPublisher(self.transport, self.runtime, self.bridge, allow_control=allow_control).start()
        self.thread = threading.Thread(target=self.bridge.run, kwargs={"timeout": 120}, daemon=True)
        self.thread.start()
        self.viewer = zenoh.open(build_config(ZenohOptions(connect=tuple(self.transport.endpoints))))

    def query(self, parameters: str = "") -> dict:
        key = keys.state_key(self.mas, "counter") + (f"?{parameters}" if parameters else "")
        for reply in self.viewer.get(key, timeout=5):
            return json.loads(reply.ok.payload.to_bytes())
        raise AssertionError("no reply")

    def control(self, command: str) -> dict:
        for reply in self.viewer.get(keys.control_key(self.mas, "counter"), payload=json.dumps({"command": command}),
                                     timeout=10):
            return json.loads(reply.ok.payload.to_bytes())
        raise AssertionError("no reply")

    def close(self) -> None:
        self.publisher.close()
        self.runtime.stop()
        self.thread.join(10)
        self.viewer.close()
        self.transport.close()


@pytest.fixture
def controllable():
    team = Team(allow_control=True)
    yield team
    team.close()


def test_pause_then_each_step_runs_exactly_one_reasoning_cycle(controllable):
    assert poll(lambda: controllable.query("summary")["cycles"] > 50, 20)
    paused = controllable.control("pause")
    assert paused["ok"] and paused["paused"]
    cycles = paused["cycles"]
    assert controllable.query("summary")["cycles"] == cycles          # held: it does not cycle
    for n in range(1, 6):
        stepped = controllable.control("step")
        assert stepped["ok"], stepped
        assert stepped["cycles"] == cycles + n
        assert controllable.query()["cycles"] == cycles + n
    resumed = controllable.control("resume")
    assert resumed["ok"] and not resumed["paused"]
    assert poll(lambda: controllable.query("summary")["cycles"] > cycles + 20, 20)


def test_the_mind_shows_beliefs_intention_stacks_and_plans_with_their_source(controllable):
    assert controllable.control("pause")["ok"]
    mind = controllable.query("plans")
    assert any(b.startswith("count(") and b.endswith("[source(self)]") for b in mind["beliefs"])
    stacks = [i["stack"] for i in mind["intention_stacks"]]
    assert stacks and stacks[0][-1]["event"] == "loop[source(self)]"          # the bottom: !loop
    assert stacks[0][-1]["source"] == "counter.asl:4"
    assert {p["source"] for p in mind["plans"]} == {"counter.asl:4", "counter.asl:5"}
    assert mind["paused"] and mind["control"]
    assert "plans" not in controllable.query()


def test_pause_is_refused_unless_the_mas_allows_it():
    team = Team(allow_control=False)
    try:
        answer = team.control("pause")
        assert not answer["ok"] and "--allow-pause" in answer["error"]
        before = team.query("summary")["cycles"]
        assert poll(lambda: team.query("summary")["cycles"] > before, 10)   # still running
    finally:
        team.close()


def test_a_malformed_state_message_is_dropped_with_a_log_line_and_the_hub_goes_on(controllable, caplog):
    hub = TeamHub(controllable.viewer, controllable.mas).start()
    try:
        hub.watch("counter")
        assert poll(lambda: "counter" in hub.minds, 10)
        stream = keys.stream_key(controllable.mas, "counter")
        percepts = f"faultmas/{controllable.mas}/robot/counter/percepts"
        with caplog.at_level(logging.WARNING, logger="faultmas.inspector"):
            for bad in (b"\xff not json", b"[1, 2]", json.dumps({"agent": "other", "cycles": 1}).encode()):
                controllable.viewer.put(stream, bad)
            controllable.viewer.put(percepts, b"{no")
            assert poll(lambda: hub.dropped >= 4, 10)
        lines = [r.getMessage() for r in caplog.records if "dropped a malformed message" in r.getMessage()]
        assert sum(stream in line for line in lines) == 3 and any(percepts in line for line in lines), lines
        hub.minds.pop("counter")
        assert poll(lambda: "counter" in hub.minds, 10)      # later good messages are still taken
        assert hub.view("counter")["mind"]["agent"] == "counter"
    finally:
        hub.close()


def test_a_mind_fetched_on_its_own_thread_after_the_session_closed_is_a_log_line_not_a_dead_thread(caplog):
    # watch, control and a missing plan library fetch a mind on a thread of its own (_refresh_in_background); the
    # session may close under it (a test's end): zenoh.ZError then ended the thread unhandled (a warning in CI)
    session = zenoh.open(build_config(ZenohOptions(listen=(loopback_endpoint(),))))
    hub = TeamHub(session, unique_mas("insp")).start()
    session.close()
    crashed: list = []
    previous, threading.excepthook = threading.excepthook, crashed.append
    try:
        with caplog.at_level(logging.WARNING, logger="faultmas.inspector"):
            worker = threading.Thread(target=hub._refresh_in_background, args=("counter",))
            worker.start()
            worker.join(10)
        assert not crashed, crashed
        assert any("counter's mind could not be fetched" in r.getMessage() for r in caplog.records)
    finally:
        threading.excepthook = previous
        hub.close()


def test_listen_is_loopback_unless_public_is_given(capsys):
    assert parse_listen("127.0.0.1:8470", False) == ("127.0.0.1", 8470)
    assert parse_listen("[::1]:0", False) == ("::1", 0)
    with pytest.raises(ValueError, match="not a loopback address; add --public"):
        parse_listen("0.0.0.0:8470", False)
    with pytest.raises(ValueError, match="HOST:PORT"):
        parse_listen("8470", False)
    assert parse_listen("0.0.0.0:8470", True) == ("0.0.0.0", 8470)
    assert "WARNING serving on 0.0.0.0, not loopback" in capsys.readouterr().err


def test_the_mind_shows_what_the_agents_observers_see(tmp_path):
    from agents.inspector.observers import observers_of
    from tests.detection.conftest import NAV_MODEL
    from tests.detection.test_agent_actions import AGENT, OBSERVERS, RULES, record_slowing_scan

    (tmp_path / "obs.yaml").write_text(OBSERVERS)
    (tmp_path / "nav.yaml").write_text(NAV_MODEL)
    (tmp_path / "nav.rules.yaml").write_text(RULES)
    record_slowing_scan(tmp_path / "run")
    runtime = LocalRuntime(printer=lambda name, text: None)
    agent = runtime.add_agent("robot", AGENT, source_file=str(tmp_path / "robot.asl"))
    runtime.run(timeout=30)          # the bag replayed: the scan slowed down, the rule asked for a repair
    [seen] = observers_of(agent)
    assert seen["config"] == "obs.yaml" and seen["obs"] == ["~hz(scan)"]
    assert seen["possibly_faulty"] == ["laser_driver"]
    assert [f["rule"] for f in seen["fired"]] == ["ask_for_repair"]
    assert [(v["observation"], v["holds"]) for v in seen["verdicts"]] == [("hz(scan)", False)]


def test_the_commands_refuse_a_taken_port_or_a_public_address_before_anything_starts():
    import socket

    from tests.agents.distributed_fixtures import Proc

    taken = socket.socket()
    taken.bind(("127.0.0.1", 0))
    taken.listen(1)
    port = taken.getsockname()[1]
    try:
        run = Proc(["run", "--inspect", "--listen", f"127.0.0.1:{port}"])
        assert run.finish(60) == 1
        assert f"cannot serve the inspector on 127.0.0.1:{port}: Address already in use" in "\n".join(run.err)
        assert not any(line.startswith("[faulty]") for line in run.out)          # no run started
    finally:
        taken.close()
    public = Proc(["inspect", "--listen", "0.0.0.0:8470"])
    assert public.finish(60) == 2
    assert "not a loopback address; add --public" in "\n".join(public.err)


def test_in_the_secure_profile_a_key_of_the_project_pauses_and_steps_and_the_minds_are_proved(tmp_path):
    """The viewer holds the environment's key (as the run's own inspector does, or ``faultmas inspect --identity``):
    its signed pause, step and resume are obeyed and the agent's signed answers and minds shown; a viewer
    without a key of the project does not even send them. (An outsider's: tests/hardening/test_run_secure_outsider.py.)"""
    from agents.transport.identity import ENVIRONMENT, Identity, generate_keys

    generate_keys(tmp_path, ["counter", "environment"])
    public = {"counter": tmp_path / "counter.pub", ENVIRONMENT: tmp_path / "environment.pub"}
    mas = unique_mas("insps")
    runtime = LocalRuntime()
    runtime.add_agent("counter", COUNTER, "counter.asl")
    transport = ZenohTransport(mas, ZenohOptions(listen=(loopback_endpoint(),)),
                               identity=Identity.from_files(public, {"counter": tmp_path / "counter.key"})).open()
    bridge = TransportBridge(runtime, transport, declared=["counter"]).attach()
    publisher = MindPublisher(transport, runtime, bridge, allow_control=True).start()
    thread = threading.Thread(target=bridge.run, kwargs={"timeout": 120}, daemon=True)
    thread.start()
    viewers = []
    try:
        for private in ({ENVIRONMENT: tmp_path / "environment.key"}, {}):
            side = ZenohTransport(mas, ZenohOptions(connect=tuple(transport.endpoints)),
                                  identity=Identity.from_files(public, private)).open()
            viewers.append((side, TeamHub(side.session, mas, transport=side).start()))
        (operator, team), (_, keyless) = viewers
        assert poll(lambda: (team.refresh("counter") or {}).get("cycles", 0) > 20, 20)
        refused = keyless.control("counter", "pause")
        assert not refused["ok"] and "--identity" in refused["error"]
        paused = team.control("counter", "pause")
        assert paused["ok"] and paused["paused"], paused
        stepped = team.control("counter", "step")
        assert stepped["ok"] and stepped["cycles"] == paused["cycles"] + 1, stepped
        assert team.refresh("counter")["cycles"] == stepped["cycles"]
        assert team.control("counter", "resume")["ok"]
        assert not operator.dropped and not transport.dropped, (operator.dropped, transport.dropped)
    finally:
        for side, hub in viewers:
            hub.close()
            side.close()
        publisher.close()
        runtime.stop()
        thread.join(10)
        transport.close()


def test_an_agent_made_at_run_time_is_inspected_until_it_is_killed(tmp_path, monkeypatch):
    """``.create_agent``: the made agent's mind is served like a launched one's; once killed, nobody answers."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "kid.asl").write_text("toy(ball).\n")
    mas = unique_mas("insp")
    runtime = LocalRuntime()
    runtime.add_agent("maker", '!make.\n+!make <- .create_agent(kid, "kid.asl").\n+!kill <- .kill_agent(kid).\n')
    transport = ZenohTransport(mas, ZenohOptions(listen=(loopback_endpoint(),))).open()
    bridge = TransportBridge(runtime, transport, declared=["maker"]).attach()
    publisher = MindPublisher(transport, runtime, bridge).start()
    thread = threading.Thread(target=bridge.run, kwargs={"timeout": 60}, daemon=True)
    thread.start()
    viewer = zenoh.open(build_config(ZenohOptions(connect=tuple(transport.endpoints))))

    def kid_state() -> dict | None:
        for reply in viewer.get(keys.state_key(mas, "kid"), timeout=2):
            if reply.ok is not None:
                return json.loads(reply.ok.payload.to_bytes())
        return None
    try:
        assert poll(lambda: kid_state() is not None, 20)
        assert "toy(ball)" in json.dumps(kid_state())
        runtime.agents["maker"].deliver(Message("maker", "maker", "achieve", Literal("kill")))
        assert poll(lambda: "kid" not in runtime.agents and "kid" not in publisher.agents, 20)
        assert kid_state() is None
    finally:
        publisher.close()
        runtime.stop()
        thread.join(10)
        viewer.close()
        bridge.detach()
        transport.close()


def report(transport: ZenohTransport, step: str) -> None:
    """A ``.progress(step)`` of agent ``a``, as an agent of another process publishes it."""
    transport.publish_control("progress", by="a", agent="a", step=step, detail="")


def test_the_timeline_keeps_the_newest_marks_numbered_for_a_reader_that_polls_from_an_offset():
    """A team held up for days: the hub keeps the newest ``timeline_marks`` (before: every report, for ever), and a
    reader asking for the marks after those it has (the page's stream) gets the right ones across the drops."""
    mas = unique_mas("tl")
    with ZenohTransport(mas) as transport:
        hub = TeamHub(transport.session, mas, timeline_marks=5).start()
        try:
            assert TeamHub(transport.session, mas).view()["timeline_limit"] == TIMELINE_MARKS   # bounded by default
            for i in range(3):
                report(transport, f"s{i}")
            assert poll(lambda: hub.view()["timeline_length"] == 3, 10)
            seen = hub.view()
            assert [m["step"] for m in seen["timeline"]] == ["s0", "s1", "s2"] and seen["timeline_dropped"] == 0
            for i in range(3, 12):
                report(transport, f"s{i}")
            assert poll(lambda: hub.view()["timeline_length"] == 12, 10)
            assert [m["step"] for m in hub.timeline] == [f"s{i}" for i in range(7, 12)]   # the newest 5
            after = hub.view(timeline_from=seen["timeline_length"])     # the reader had s0-s2; s3-s6 are gone
            assert [m["step"] for m in after["timeline"]] == [f"s{i}" for i in range(7, 12)]
            assert (after["timeline_first"], after["timeline_dropped"], after["timeline_length"]) == (7, 7, 12)
            assert [m["step"] for m in hub.view(timeline_from=10)["timeline"]] == ["s10", "s11"]
            assert hub.view(timeline_from=12)["timeline"] == []
        finally:
            hub.close()
    with pytest.raises(ValueError, match="timeline_marks must be at least 1"):
        TeamHub(None, mas, timeline_marks=0)
