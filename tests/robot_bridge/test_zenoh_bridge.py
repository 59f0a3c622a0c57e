"""ZenohBridge <-> SimServer over a real Zenoh session on loopback: actions complete when the motion ends,
percepts arrive, bad requests are dropped, a silent robot fails actions with ``timeout``."""
from __future__ import annotations

import pytest

zenoh = pytest.importorskip("zenoh")

from agents.transport.config import ZenohOptions, build_config, loopback_endpoint  # noqa: E402
from robot_bridge import Action  # noqa: E402
from robot_bridge.sim.bridge import SimBridge  # noqa: E402
from robot_bridge.sim.server import SimServer  # noqa: E402
from robot_bridge.sim.world import World  # noqa: E402
from robot_bridge.zenoh_bridge import ZenohBridge, robot_key  # noqa: E402


@pytest.fixture(scope="module")
def served():
    endpoint = loopback_endpoint()
    session = zenoh.open(build_config(ZenohOptions(listen=(endpoint,))))
    world = World(seed=2)
    bridges = {"faulty": SimBridge("faulty", world=world, fault="encoders"),
               "helper": SimBridge("helper", world=world, y=-1.5, yaw_deg=90.0, camera=True)}
    for bridge in bridges.values():
        bridge.setup()
    server = SimServer(session, "zb", bridges).start()
    yield endpoint, session, server, world
    server.stop()
    session.close()
    for bridge in bridges.values():
        bridge.shutdown()


def test_a_remote_move_fails_as_the_simulated_one_does_and_percepts_follow(served):
    endpoint, _, _, world = served
    bridge = ZenohBridge("faulty", mas="zb", connect=(endpoint,))
    bridge.setup(timeout=10)
    try:
        done = bridge.act(Action("move", (0.5,))).result(20)
        assert (done.ok, done.reason) == (False, "no_progress")
        names = {p.name for p in bridge.percepts()}
        assert {"odom", "encoders", "stopped"} <= names
        assert world.pose("faulty")[0] > 0.05          # it drove; its encoders said nothing
        assert bridge.act(Action("fly")).result(5).reason == "unknown_action"
        assert bridge.act(Action("move", ("far",))).result(5).reason == "bad_args"
    finally:
        bridge.shutdown()


def test_the_camera_percepts_cross_the_network(served):
    endpoint, *_ = served
    bridge = ZenohBridge("helper", mas="zb", connect=(endpoint,))
    bridge.setup(timeout=10)
    try:
        import time
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and not any(p.name == "robot_seen" for p in bridge.percepts()):
            time.sleep(0.05)
        seen = [p for p in bridge.percepts() if p.name == "robot_seen"]
        assert seen and seen[0].args[0] == "faulty" and 1.2 < seen[0].args[2] < 1.7
    finally:
        bridge.shutdown()


def test_a_malformed_request_is_dropped_and_the_server_keeps_serving(served, caplog):
    endpoint, session, server, _ = served
    before = server.requests
    session.put(robot_key("zb", "faulty", "actions"), "not json")
    bridge = ZenohBridge("faulty", mas="zb", connect=(endpoint,))
    bridge.setup(timeout=10)
    try:
        assert bridge.act(Action("stop")).result(10).ok
        assert server.requests >= before + 2
    finally:
        bridge.shutdown()


def test_no_server_means_setup_names_the_key_and_a_silent_robot_times_out():
    endpoint = loopback_endpoint()
    session = zenoh.open(build_config(ZenohOptions(listen=(endpoint,))))
    try:
        bridge = ZenohBridge("ghost", mas="zb", session=session)
        with pytest.raises(TimeoutError, match="faultmas/zb/robot/ghost/percepts"):
            bridge.setup(timeout=0.3)
        # a server that publishes percepts but never answers actions
        session.put(robot_key("zb", "mute", "percepts"), '{"source":"sim","literals":["stopped"]}')
        mute = ZenohBridge("mute", mas="zb", session=session, action_timeout=0.3)
        publisher = session.declare_publisher(robot_key("zb", "mute", "percepts"))
        import threading
        stop = threading.Event()
        feeder = threading.Thread(target=lambda: [publisher.put('{"source":"sim","literals":["stopped"]}')
                                                  for _ in iter(lambda: stop.wait(0.05), True)], daemon=True)
        feeder.start()
        try:
            mute.setup(timeout=5)
            done = mute.act(Action("move", (1.0,))).result(5)
            assert (done.ok, done.reason) == (False, "timeout")
        finally:
            stop.set()
            mute.shutdown()
    finally:
        session.close()


def test_the_bridges_clock_is_the_servers_and_an_actions_time_bound_counts_in_it(caplog):
    """A simulator 20 times slower than real time: a move's bound (0.3 s here) is simulated seconds, so the
    move is still pending after a wall second; it fails once the server's clock passes the bound. A bad
    clock message is dropped with a log line."""
    import threading
    import time

    from robot_bridge.zenoh_bridge import clock_key

    endpoint = loopback_endpoint()
    session = zenoh.open(build_config(ZenohOptions(listen=(endpoint,))))
    percepts = session.declare_publisher(robot_key("zc", "slow", "percepts"))
    ticks = session.declare_publisher(clock_key("zc"))
    sim = [10.0]
    stop = threading.Event()

    def serve() -> None:
        while not stop.wait(0.05):
            percepts.put('{"source":"sim","literals":["stopped"]}')
            ticks.put(repr(sim[0]))
            sim[0] += 0.0025
    server = threading.Thread(target=serve, daemon=True)
    server.start()
    bridge = ZenohBridge("slow", mas="zc", session=session, action_timeout=0.3)
    try:
        bridge.setup(timeout=5)
        deadline = time.monotonic() + 5
        while not bridge._clock.following and time.monotonic() < deadline:
            time.sleep(0.02)
        start = bridge.clock()
        pending = bridge.act(Action("move", (1.0,)))
        time.sleep(1.0)
        assert not pending.done()
        assert 0.0 < bridge.clock() - start < 0.2
        session.put(clock_key("zc"), "soon")          # dropped, named
        sim[0] += 1.0
        done = pending.result(5)
        assert (done.ok, done.reason) == (False, "timeout")
        assert any("bad clock message" in r.getMessage() for r in caplog.records)
    finally:
        stop.set()
        server.join(2)
        bridge.shutdown()
        session.close()


def test_an_action_completes_after_the_snapshot_its_server_sent_before_the_status():
    """The server sends a robot's last percepts, then the action's status (``SimServer._answer``); an agent
    that sees the action completed must perceive that snapshot, not an older one. zenoh-python runs each
    subscriber's callbacks on a thread of its own, so two subscribers (status, percepts) could reorder them:
    with ``--processes`` an agent read ``odom`` from before a ``move`` right after it completed (1 run in 4)."""
    import json
    import threading

    endpoint = loopback_endpoint()
    server = zenoh.open(build_config(ZenohOptions(listen=(endpoint,))))
    percepts = server.declare_publisher(robot_key("zo", "r", "percepts"))
    status = server.declare_publisher(robot_key("zo", "r", "status"))

    def snapshot(n: int) -> str:
        return json.dumps({"source": "sim", "literals": [f"odom({n},0,0)"], "ttl": 60})

    current = [-1]      # the robot's state: what every snapshot says, the periodic ones too (as the server's)

    def answer(sample) -> None:     # as SimServer._answer: the final snapshot, then the status
        request = json.loads(sample.payload.to_bytes())
        current[0] = request["id"]
        percepts.put(snapshot(request["id"]))
        status.put(json.dumps({"agent_name": "r", "id": request["id"], "result": True}))

    requests = server.declare_subscriber(robot_key("zo", "r", "actions"), answer)
    stop = threading.Event()
    feeder = threading.Thread(target=lambda: [percepts.put(snapshot(current[0])) for _ in iter(lambda: stop.wait(0.05), True)],
                              daemon=True)
    feeder.start()
    bridge = ZenohBridge("r", mas="zo", connect=(endpoint,))
    try:
        bridge.setup(timeout=10)
        stale = []
        for _ in range(150):
            action = Action("move", (0.1,))
            assert bridge.act(action).result(10).ok
            seen = [p.args[0] for p in bridge.percepts() if p.name == "odom"]
            if seen != [action.id]:
                stale.append((action.id, seen))
        assert not stale, f"{len(stale)} of 150 actions completed before their snapshot: {stale[:5]}"
    finally:
        stop.set()
        bridge.shutdown()
        requests.undeclare()
        server.close()
