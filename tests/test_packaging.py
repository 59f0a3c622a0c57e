"""Packaging as a library user expects (issue 23): an SPDX license with its file, classifiers, published
ranges with the exact pins in constraints.txt (what the Makefile installs), and no runtime dependency that
nothing imports."""
from __future__ import annotations

import ast
import sys
from importlib.metadata import packages_distributions
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

if sys.version_info >= (3, 11):
    import tomllib
else:                                                   # pragma: no cover
    tomllib = pytest.importorskip("tomli")

REPO = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
PINS = {canonicalize_name(r.name): r for r in (
    Requirement(line.split("#")[0].strip()) for line in (REPO / "constraints.txt").read_text().splitlines()
    if line.split("#")[0].strip())}
REQUIREMENTS = [Requirement(r) for r in PROJECT["dependencies"]] + [
    Requirement(r) for extra in PROJECT["optional-dependencies"].values() for r in extra]


def test_license_is_an_spdx_string_with_its_file() -> None:
    assert PROJECT["license"] == "Apache-2.0"
    assert PROJECT["license-files"] == ["LICENSE"] and "Apache License" in (REPO / "LICENSE").read_text()[:200]
    assert any(c.startswith("Programming Language :: Python :: 3") for c in PROJECT["classifiers"])


def test_published_requirements_are_ranges_and_every_one_is_pinned_within_its_range() -> None:
    exact = [str(r) for r in REQUIREMENTS if any(s.operator in ("==", "===") for s in r.specifier)]
    assert exact == []
    unpinned = [r.name for r in REQUIREMENTS if canonicalize_name(r.name) not in PINS]
    assert unpinned == []
    for r in REQUIREMENTS:
        [pin] = PINS[canonicalize_name(r.name)].specifier
        assert pin.operator == "==" and r.specifier.contains(pin.version, prereleases=True), (r, pin)


def test_no_runtime_dependency_is_left_that_nothing_imports() -> None:
    imported: set[str] = set()
    for package in ("agentspeak", "agents", "diagnosis", "detection", "experiments", "perception",
                                "plans", "robot_bridge"):
        for path in (REPO / package).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.Import):
                    imported |= {a.name.split(".")[0] for a in node.names}
                elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                    imported.add(node.module.split(".")[0])
    owners = packages_distributions()
    used = {canonicalize_name(d) for module in imported for d in owners.get(module, ())}
    unused = [r.name for r in map(Requirement, PROJECT["dependencies"]) if canonicalize_name(r.name) not in used]
    assert unused == []
