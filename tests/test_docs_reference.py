"""docs/fault-plans.md is the fault-plan author's reference: it names every internal action faultmas adds,
every percept and every action, so a new one without documentation fails here (issue 23)."""
from __future__ import annotations

from pathlib import Path

DOC = (Path(__file__).resolve().parents[1] / "docs" / "fault-plans.md").read_text(encoding="utf-8")


def test_every_percept_and_action_is_in_the_reference() -> None:
    from robot_bridge.actions import ACTIONS, REASONS
    from robot_bridge.percepts import VOCABULARY

    missing = [f"percept {name}" for name, _ in VOCABULARY if f"`{name}" not in DOC]
    missing += [f"action {name}" for name in ACTIONS if f"`{name}" not in DOC]
    missing += [f"reason {name}" for name in REASONS if f"`{name}`" not in DOC]
    assert missing == []


def test_every_plug_in_internal_action_is_in_the_reference() -> None:
    from agentspeak.stdlib.registry import Registry, STDLIB

    before = set(Registry().names())          # a fresh registry: nothing
    STDLIB.load_extensions()
    from importlib.metadata import entry_points
    plug_in_modules = {ep.value for ep in entry_points(group="faultmas.internal_actions")}
    added = [spec.name for spec in STDLIB.actions.values()
             if getattr(spec.function, "__module__", "") in plug_in_modules]
    assert added and not before
    assert [name for name in added if f"`{name}(" not in DOC] == []


def test_no_doc_points_outside_the_repository() -> None:
    """A user has the repository (or the installed package) only: a relative path that leaves it is a dead end."""
    import re

    repo = Path(__file__).resolve().parents[1]
    leaving = []
    for doc in [repo / "README.md", *sorted((repo / "docs").glob("*.md")), *sorted(repo.glob("*/README.md"))]:
        text = doc.read_text(encoding="utf-8")
        for match in re.finditer(r"(?<![\w/.])(?:\.\./)+[\w.-]+", text):
            # a Markdown link is relative to its file; a path in the text, to the repository (as `tests/`)
            base = doc.parent if text[:match.start()].endswith("](") else repo
            target = (base / match.group(0)).resolve()
            if repo not in target.parents:
                leaving.append(f"{doc.relative_to(repo)}: {match.group(0)}")
    assert leaving == []
