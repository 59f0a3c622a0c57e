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
