"""The compiled interpreter (agentspeak/_speedups.py): used when built, never when its source changed since,
never with FAULTMAS_PURE_PYTHON=1. Each case imports in a fresh interpreter, as a user's process would."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from agentspeak import _speedups

PACKAGE = Path(_speedups.__file__).resolve().parent
BUILT = (PACKAGE / _speedups.MANIFEST).exists()


def _where(modules: list[str], cwd: Path, pure: bool = False) -> tuple[dict[str, str], str]:
    """Import ``modules`` in a new process started in ``cwd`` (whose ``agentspeak`` comes first on the path)."""
    env = {k: v for k, v in os.environ.items() if k != _speedups.PURE_ENV}
    if pure:
        env[_speedups.PURE_ENV] = "1"
    env["PYTHONPATH"] = str(cwd)
    code = ("import importlib, json, sys\n"
            f"print(json.dumps({{m: importlib.import_module(m).__file__ for m in {modules!r}}}))")
    done = subprocess.run([sys.executable, "-c", code], cwd=cwd, env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout), done.stderr


def test_every_listed_module_exists_and_is_not_this_guard():
    for module in _speedups.COMPILED_MODULES:
        assert _speedups.source_path(module).is_file(), module
    assert "agentspeak._speedups" not in _speedups.COMPILED_MODULES


@pytest.mark.skipif(not sysconfig.get_config_var("CC"), reason="no C compiler: the interpreter runs from source")
def test_a_machine_with_a_compiler_runs_the_compiled_interpreter():
    assert BUILT, f"no {_speedups.MANIFEST}: run {_speedups.REBUILD}"
    files, stderr = _where(list(_speedups.COMPILED_MODULES), PACKAGE.parent)
    assert not [m for m, f in files.items() if f.endswith(".py")], stderr
    assert "not built from the source" not in stderr


@pytest.mark.skipif(not BUILT, reason="the compiled interpreter is not built")
def test_pure_python_switch_loads_every_module_from_source():
    files, _ = _where(list(_speedups.COMPILED_MODULES), PACKAGE.parent, pure=True)
    assert all(f.endswith(".py") for f in files.values()), files


@pytest.mark.skipif(not BUILT, reason="the compiled interpreter is not built")
def test_an_edited_module_runs_from_source_with_a_warning(tmp_path):
    copy = tmp_path / "agentspeak"
    shutil.copytree(PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    edited = copy / "fork.py"
    edited.write_text(edited.read_text() + "\nEDITED_AFTER_THE_BUILD = True\n")
    files, stderr = _where(["agentspeak.fork", "agentspeak.unify"], tmp_path)
    assert files["agentspeak.fork"] == str(edited)
    assert not files["agentspeak.unify"].endswith(".py")          # untouched modules stay compiled
    assert "agentspeak.fork" in stderr and "make speedups" in stderr


@pytest.mark.skipif(not BUILT, reason="the compiled interpreter is not built")
def test_a_compiled_file_the_last_build_did_not_make_is_not_used(tmp_path):
    copy = tmp_path / "agentspeak"
    shutil.copytree(PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    manifest = json.loads((copy / _speedups.MANIFEST).read_text())
    del manifest["agentspeak.unify"]                 # as if left by an older build that listed it
    (copy / _speedups.MANIFEST).write_text(json.dumps(manifest))
    files, stderr = _where(["agentspeak.unify", "agentspeak.fork"], tmp_path)
    assert files["agentspeak.unify"] == str(copy / "unify.py")
    assert not files["agentspeak.fork"].endswith(".py")
    assert "agentspeak.unify" in stderr


def test_describe_names_how_the_interpreter_runs():
    import agentspeak.solver  # noqa: F401  (a listed module, loaded)
    text = _speedups.describe()
    compiled = not agentspeak.solver.__file__.endswith(".py")
    assert text.startswith("compiled") if compiled else text == "pure Python"
