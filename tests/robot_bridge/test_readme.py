"""The examples of robot_bridge/README.md run as written: a user's bridge added through an entry point."""
import importlib
import re
import sys
import tomllib
from pathlib import Path

import pytest

import robot_bridge
from robot_bridge import Action

README = Path(robot_bridge.__file__).parent / "README.md"


def block(tag: str, language: str) -> str:
    """The first ``language`` code block after the ``<!-- tested: tag`` marker."""
    text = README.read_text()
    start = text.index(f"<!-- tested: {tag}")
    match = re.compile(rf"```{language}\n(.*?)```", re.S).search(text, start)
    return match.group(1)


def test_custom_bridge_example_installs_and_runs(tmp_path, monkeypatch):
    code = block("custom-bridge", "python")
    toml = block("custom-bridge", "toml")
    (name, target), = tomllib.loads(toml)["project"]["entry-points"]["faultmas.robot_bridges"].items()
    module = target.partition(":")[0]
    (tmp_path / f"{module}.py").write_text(code)
    info = tmp_path / f"{module}-0.1.dist-info"       # what `pip install` leaves behind
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {module}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[faultmas.robot_bridges]\n{name} = {target}\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    try:
        assert name in robot_bridge.available()
        bridge = robot_bridge.create(name, "faulty")
        bridge.setup()
        assert bridge.act(Action("move", (0.5,))).result(0).ok
        assert bridge.act(Action("move", ("far",))).result(0).reason == "bad_args"
        assert bridge.act(Action("dance")).result(0).reason == "unknown_action"
        assert bridge.done == ["move(0.5)"]
        bridge.shutdown()
    finally:
        sys.modules.pop(module, None)


def test_simulator_example_runs(capsys):
    exec(compile(block("sim-example", "python"), str(README), "exec"), {})
    lines = capsys.readouterr().out.splitlines()
    assert "reason='no_progress'" in lines[0]
    assert "Percept(name='robot_seen', args=('faulty'" in lines[2]
