"""Finding bridges by name: built-in entry points, a user's own entry point, module:Class strings."""
import importlib
import sys
import textwrap

import pytest

import robot_bridge
from robot_bridge import Action, registry
from robot_bridge.logging_bridge import LoggingBridge
from robot_bridge.sim.bridge import SimBridge


def test_builtin_bridges_are_found_by_name():
    assert {"sim", "ros2"} <= set(registry.available())
    assert registry.load("sim") is SimBridge


def test_unknown_name_lists_the_known_ones():
    with pytest.raises(registry.UnknownBridgeError,
                       match=r"unknown robot bridge 'simm'; known bridges: .*ros2.*sim"):
        registry.load("simm")


def test_module_class_strings():
    assert registry.load("robot_bridge.logging_bridge:LoggingBridge") is LoggingBridge
    with pytest.raises(registry.UnknownBridgeError, match="no module 'robot_bridge.nothing'"):
        registry.load("robot_bridge.nothing:X")
    with pytest.raises(registry.UnknownBridgeError, match="has no 'Nope'"):
        registry.load("robot_bridge.logging_bridge:Nope")
    with pytest.raises(TypeError, match="not a subclass of robot_bridge.RobotBridge"):
        registry.load("robot_bridge.protocol:Action")


@pytest.fixture
def installed_plugin(tmp_path, monkeypatch):
    """A distribution 'mybots' with a bridge 'printer', installed the way pip would: a *.dist-info on sys.path."""
    package = tmp_path / "mybots"
    package.mkdir()
    (package / "__init__.py").write_text(textwrap.dedent('''
        from robot_bridge.logging_bridge import LoggingBridge

        class PrinterBridge(LoggingBridge):
            name = "printer"
    '''))
    info = tmp_path / "mybots-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: mybots\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[faultmas.robot_bridges]\nprinter = mybots:PrinterBridge\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    yield
    sys.modules.pop("mybots", None)


def test_a_users_bridge_is_found_through_the_entry_point_group(installed_plugin):
    assert "printer" in registry.available()
    bridge = robot_bridge.create("printer", "faulty")
    assert type(bridge).__name__ == "PrinterBridge"
    bridge.setup()
    assert bridge.act(Action("move", (0.5,))).result(0).ok
    assert bridge.act(Action("moov", (0.5,))).result(0).reason == "unknown_action"
    assert [str(a) for a in bridge.log] == ["move(0.5)"]
    bridge.shutdown()


def test_an_unknown_option_is_refused_with_the_bridges_options():
    with pytest.raises(registry.UnknownBridgeOptionError,
                       match=r"robot bridge 'sim' has no option 'fualt'; its options: .*camera.*fault.*speed"):
        robot_bridge.create("sim", "faulty", fualt="encoders")
    with pytest.raises(registry.UnknownBridgeOptionError, match=r"'ros2' has no option 'domain'; .*domain_id"):
        robot_bridge.create("ros2", "faulty", domain=3)
    with pytest.raises(registry.UnknownBridgeOptionError, match=r"its options: none"):
        robot_bridge.create("robot_bridge.logging_bridge:LoggingBridge", "faulty", speed=1)
    assert robot_bridge.create("sim", "faulty", fault="encoders", seed=2).robot == "faulty"


def test_options_come_from_the_declaration_or_the_constructor():
    assert {"world", "fault", "camera", "speed"} <= set(registry.known_options(SimBridge))
    assert registry.known_options(SimBridge)["speed"] == "default 0.0"
    assert set(registry.known_options(registry.load("zenoh"))) == {"mas", "session", "connect", "action_timeout"}
    assert "domain_id" in registry.known_options(registry.load("ros2"))


def test_command_line_options_become_values():
    assert registry.parse_options(["seed=3", "speed=0.5", "camera=true", "mas=coop", "seed=4"]) == \
        {"seed": 4, "speed": 0.5, "camera": True, "mas": "coop"}
    with pytest.raises(ValueError, match="KEY=VALUE, got 'seed'"):
        registry.parse_option("seed")


def test_a_simulated_team_shares_one_world_side_by_side():
    team = robot_bridge.create_team("sim", ["faulty", "helper", "third"], seed=5)
    worlds = {id(bridge.world) for bridge in team.values()}
    assert len(worlds) == 1
    for bridge in team.values():
        bridge.setup()
    try:
        world = team["faulty"].world
        assert [world.pose(name)[:2] for name in team] == [(0.0, 0.0), (0.0, -1.5), (0.0, -3.0)]
    finally:
        for bridge in team.values():
            bridge.shutdown()
    with pytest.raises(registry.UnknownBridgeOptionError):
        robot_bridge.create_team("sim", ["a"], sped=1)
