"""docs/bridges.md's example runs as written: a bridge subclass that adds a percept, chosen by a project's
``environment:`` line through its dotted Python name."""
from __future__ import annotations

import importlib
import re
import sys
from pathlib import Path

from agents.cli import main

DOC = Path(__file__).resolve().parents[2] / "docs" / "bridges.md"


def blocks(tag: str) -> list[str]:
    """The code blocks after the ``<!-- tested: tag`` marker, up to the next heading."""
    text = DOC.read_text(encoding="utf-8")
    start = text.index(f"<!-- tested: {tag}")
    return re.findall(r"```\w*\n(.*?)```", text[start:text.find("\n## ", start)], re.S)


def test_the_battery_example_perceives_its_own_percept(tmp_path, monkeypatch, capsys) -> None:
    python, plan, project = blocks("battery")
    (tmp_path / "batterysim.py").write_text(python)
    (tmp_path / "lowbattery.asl").write_text(plan)
    (tmp_path / "lowbattery.mas2j").write_text(project)
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    try:
        code = main(["mas", "run", str(tmp_path / "lowbattery.mas2j"), "--timeout", "60"])
    finally:
        sys.modules.pop("batterysim", None)
    out = capsys.readouterr().out
    assert code == 0, out
    level = re.fullmatch(r"\[rover\] battery low: (\d+)%\n", out)
    assert level and 0 <= int(level.group(1)) < 98, out
