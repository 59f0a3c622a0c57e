"""detection/ feeds diagnosis/ and never imports agents/ (the architecture's one-way imports)."""
from __future__ import annotations

import ast
from pathlib import Path

DETECTION = Path(__file__).resolve().parents[2] / "detection"


def imported_modules(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


def test_detection_never_imports_agents():
    offenders = {str(p.relative_to(DETECTION)): sorted(m for m in imported_modules(p) if m.split(".")[0] == "agents")
                 for p in DETECTION.rglob("*.py")}
    assert {p: m for p, m in offenders.items() if m} == {}
    assert len(offenders) > 10          # the scan did look at the package
