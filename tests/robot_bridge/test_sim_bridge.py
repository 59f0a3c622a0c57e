"""SimBridge through the protocol, with the runner thread pacing the clock (no timed assertions)."""
import pytest

from robot_bridge import Action, percepts
from robot_bridge.sim.bridge import SimBridge
from robot_bridge.sim.world import World

WAIT = 20.0   # wall seconds a future may take at most; generous, only guards against a hang


@pytest.fixture
def bridge():
    b = SimBridge("faulty", seed=1)
    b.setup()
    yield b
    b.shutdown()


def test_actions_complete_when_the_motion_is_done(bridge):
    assert bridge.act(Action("move", (0.4,))).result(WAIT).ok
    assert bridge.act(Action("turn", (90,))).result(WAIT).ok
    x, y, yaw = bridge.world.pose("faulty")
    assert x == pytest.approx(0.4, abs=0.03) and yaw == pytest.approx(90, abs=3)
    odom = next(p for p in bridge.percepts() if p.name == "odom")
    assert odom.args[0] == pytest.approx(x, abs=0.02) and odom.args[2] == pytest.approx(yaw, abs=2)


@pytest.mark.parametrize("action, reason", [
    (Action("fly"), "unknown_action"),
    (Action("move", ("far",)), "bad_args"),
    (Action("move", (1.0, 5.0)), "bad_args"),           # faster than a Kobuki
    (Action("move", ()), "bad_args"),
    (Action("turn", (True,)), "bad_args"),
    (Action("set_fault", ("broken",)), "bad_args"),
])
def test_malformed_actions_fail_at_once(bridge, action, reason):
    future = bridge.act(action)
    assert future.done()
    assert (future.result().ok, future.result().reason) == (False, reason)
    assert str(action.args[0] if action.args else action.name) in future.result().detail \
        or "arguments" in future.result().detail


def test_set_fault_action_then_move_fails_as_faulty_detects_it(bridge):
    assert bridge.act(Action("set_fault", ("encoders",))).result(WAIT).ok
    result = bridge.act(Action("move", (0.5,))).result(WAIT)
    assert (result.ok, result.reason) == (False, "no_progress")
    assert bridge.world.pose("faulty")[0] > 0.1


def test_shutdown_fails_pending_actions():
    b = SimBridge("r", speed=1.0)      # real time: a 25 m move is still running when we shut down
    b.setup()
    future = b.act(Action("move", (25.0,)))
    b.shutdown()
    assert (future.result(WAIT).ok, future.result().reason) == (False, "shutdown")
    assert b.act(Action("stop")).result(WAIT).reason == "shutdown"


def test_bridges_share_one_world_and_clock():
    world = World(seed=2)
    a = SimBridge("a", world=world, x=-1.0)
    b = SimBridge("b", world=world, x=1.0, yaw_deg=180.0, camera=False)
    a.setup()
    b.setup()
    try:
        fa, fb = a.act(Action("move", (0.5,))), b.act(Action("turn", (-45,)))
        assert fa.result(WAIT).ok and fb.result(WAIT).ok
        assert world.robots == ["a", "b"]
        assert world.pose("a")[0] == pytest.approx(-0.5, abs=0.03)
        assert world.pose("b")[2] == pytest.approx(135.0, abs=3)
        for p in a.percepts() + b.percepts():
            percepts.validate(p)
    finally:
        a.shutdown()
        b.shutdown()


def test_manual_clock_gives_the_caller_control():
    world = World(noise=False)
    b = SimBridge("r", world=world, drive=False)
    b.setup()
    future = b.act(Action("move", (0.2,)))
    assert not future.done() and world.time == 0.0
    world.run_until(future.done, 10)
    assert future.result().ok and world.time > 1.0
