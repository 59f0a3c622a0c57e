"""The compiled interpreter (agentspeak/_speedups.py): used when built, never when its source changed since,
never with FAULTMAS_PURE_PYTHON=1. Each case imports in a fresh interpreter, as a user's process would."""
from __future__ import annotations

import importlib
import importlib.machinery
import json
import re
import os
import shutil
import subprocess
import sys
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
        assert os.path.isfile(_speedups.source_path(module)), module
    assert "agentspeak._speedups" not in _speedups.COMPILED_MODULES


@pytest.mark.skipif(not _speedups.c_compiler_available(), reason="no C compiler: the interpreter runs from source")
def test_a_machine_with_a_compiler_runs_the_compiled_interpreter():
    assert BUILT, f"no {_speedups.MANIFEST}: run {_speedups.REBUILD}"
    files, stderr = _where(list(_speedups.COMPILED_MODULES), PACKAGE.parent)
    assert not [m for m, f in files.items() if f.endswith(".py")], stderr
    assert "not built from the source" not in stderr


@pytest.mark.skipif(not BUILT, reason="the compiled interpreter is not built")
def test_pure_python_switch_loads_every_module_from_source():
    files, _ = _where(list(_speedups.COMPILED_MODULES), PACKAGE.parent, pure=True)
    assert all(f.endswith(".py") for f in files.values()), files


def _copy_of_the_package(tmp_path: Path) -> Path:
    copy = tmp_path / "agentspeak"
    shutil.copytree(PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    return copy


@pytest.mark.skipif(not BUILT, reason="the compiled interpreter is not built")
def test_an_edited_module_runs_the_whole_interpreter_from_source_with_a_warning(tmp_path):
    copy = _copy_of_the_package(tmp_path)
    edited = copy / "fork.py"
    edited.write_text(edited.read_text() + "\nEDITED_AFTER_THE_BUILD = True\n")
    files, stderr = _where(["agentspeak.fork", "agentspeak.unify", "agentspeak.agent"], tmp_path)
    assert files["agentspeak.fork"] == str(edited)
    # all or none: compiled modules share C types, so untouched ones run from source too
    assert files["agentspeak.unify"] == str(copy / "unify.py")
    assert files["agentspeak.agent"] == str(copy / "agent.py")
    assert "agentspeak.fork" in stderr and "make speedups" in stderr
    assert "agentspeak.unify" not in stderr                        # the warning names what changed


@pytest.mark.skipif(not BUILT, reason="the compiled interpreter is not built")
def test_the_check_runs_before_the_first_compiled_module_also_after_plain_ones(tmp_path):
    """The guard checks when a compiled module is first looked for (not at ``import agentspeak``): a process that
    imports only plain modules (``faultmas diagnose``) skips it, one that imports plain modules first still gets
    every compiled module from source once one source changed."""
    copy = _copy_of_the_package(tmp_path)
    edited = copy / "fork.py"
    edited.write_text(edited.read_text() + "\nEDITED_AFTER_THE_BUILD = True\n")
    files, stderr = _where(["agentspeak.errors", "agentspeak.source_text", "agentspeak.user_cache"], tmp_path)
    assert all(f.endswith(".py") for f in files.values()) and "make speedups" not in stderr
    files, stderr = _where(["agentspeak.errors", "agentspeak.source_text", "agentspeak.unify", "agentspeak.fork"],
                           tmp_path)
    assert files["agentspeak.unify"] == str(copy / "unify.py") and files["agentspeak.fork"] == str(edited)
    assert "agentspeak.fork" in stderr and "make speedups" in stderr


@pytest.mark.skipif(not BUILT, reason="the compiled interpreter is not built")
def test_an_edited_declaration_file_counts_as_an_edited_module(tmp_path):
    copy = _copy_of_the_package(tmp_path)
    declarations = copy / "intentions.pxd"
    assert declarations.exists(), "the C types of Frame, Intention ... are declared there"
    declarations.write_text(declarations.read_text() + "\n# edited after the build\n")
    files, stderr = _where(["agentspeak.intentions", "agentspeak.agent"], tmp_path)
    assert all(f.endswith(".py") for f in files.values()), files
    assert "agentspeak.intentions" in stderr


@pytest.mark.skipif(not BUILT, reason="the compiled interpreter is not built")
def test_a_compiled_file_the_last_build_did_not_make_is_not_used(tmp_path):
    copy = _copy_of_the_package(tmp_path)
    manifest = json.loads((copy / _speedups.MANIFEST).read_text())
    del manifest["agentspeak.unify"]                 # as if left by an older build that listed it
    (copy / _speedups.MANIFEST).write_text(json.dumps(manifest))
    files, stderr = _where(["agentspeak.unify", "agentspeak.fork"], tmp_path)
    assert files["agentspeak.unify"] == str(copy / "unify.py")
    assert files["agentspeak.fork"] == str(copy / "fork.py")
    assert "agentspeak.unify" in stderr


@pytest.mark.skipif(not BUILT, reason="the compiled interpreter is not built")
def test_a_module_the_build_could_not_compile_runs_the_whole_interpreter_from_source(tmp_path):
    copy = _copy_of_the_package(tmp_path)
    compiled = _speedups.compiled_files(copy)
    os.remove(compiled["agentspeak.intentions"])     # as if its C compile had failed (extensions are optional)
    files, stderr = _where(["agentspeak.intentions", "agentspeak.agent"], tmp_path)
    assert all(f.endswith(".py") for f in files.values()), files   # agent.so needs intentions' C types
    assert "agentspeak.intentions" in stderr


def test_describe_names_how_the_interpreter_runs():
    import agentspeak.solver  # noqa: F401  (a listed module, loaded)
    text = _speedups.describe()
    compiled = not agentspeak.solver.__file__.endswith(".py")
    assert text.startswith("compiled") if compiled else text == "pure Python"


def _declared_fields(pxd: Path) -> dict[str, set[str]]:
    """``cdef class X:`` blocks of a .pxd -> the names of their ``cdef public object`` fields."""
    fields: dict[str, set[str]] = {}
    current = None
    for line in pxd.read_text().splitlines():
        head = re.match(r"cdef class (\w+):", line)
        if head:
            current = fields.setdefault(head.group(1), set())
        elif not line.startswith((" ", "\t")) and line.strip():
            current = None
        elif current is not None and line.strip().startswith("cdef public object "):
            current.update(n.strip() for n in line.strip()[len("cdef public object "):].split(","))
    return fields


@pytest.mark.parametrize("pxd", sorted(p.name for p in PACKAGE.glob("*.pxd")))
def test_the_c_types_declare_exactly_the_slots_of_their_classes(pxd):
    module = importlib.import_module(f"agentspeak.{pxd[:-4]}")
    for name, declared in _declared_fields(PACKAGE / pxd).items():
        slots = getattr(getattr(module, name), "__slots__", None)
        if slots is None:           # a class with a __dict__ (Agent): its declared fields must be set in __init__
            source = (PACKAGE / f"{pxd[:-4]}.py").read_text()
            unset = [f for f in declared if not re.search(rf"self\.{f}\b(\s*:[^=\n]*)?\s*=", source)]
            assert not unset, (name, unset)
        else:               # (Agent's slots end with __dict__: users and bridges add attributes)
            assert declared == set(slots) - {"__weakref__", "__dict__"}, name


def test_a_python_subclass_of_agent_overrides_the_compiled_cycle_and_adds_attributes():
    """Agent is a C type when compiled (agent.pxd); a subclass's methods must still be the ones called."""
    from agentspeak.agent import Agent
    from agentspeak.parser import parse_program
    from agentspeak.runtime import LocalArch, LocalRuntime

    class Counting(Agent):
        def act(self):
            self.acts = getattr(self, "acts", 0) + 1      # an attribute Agent does not declare
            super().act()

        def cycle(self):
            self.cycles_seen = getattr(self, "cycles_seen", 0) + 1
            return super().cycle()

    lines = []
    runtime = LocalRuntime(printer=lambda name, text: lines.append(text))
    agent = Counting("c", arch=LocalArch(runtime))
    agent.load(parse_program('!g(3). +!g(0) <- .print(done). +!g(N) <- !g(N - 1).', "<test>"))
    runtime.agents["c"] = agent
    runtime.wake(agent)
    assert runtime.run(timeout=10) == "idle"
    assert lines == ["done"]
    assert agent.acts >= 4 and agent.cycles_seen >= agent.acts


def _fake_build(tmp_path: Path, digest_ok: bool, stamp_ok: bool) -> Path:
    """A package ``agentspeak`` with one module and a compiled file beside it (never imported here), and a
    manifest whose digest and stamp of that module are right or wrong as asked."""
    package = tmp_path / "agentspeak"
    package.mkdir()
    source = package / "fork.py"
    source.write_text("X = 1\n")
    (package / f"fork{importlib.machinery.EXTENSION_SUFFIXES[0]}").write_bytes(b"")
    record = {"agentspeak.fork": _speedups.source_digest(source) if digest_ok else "0" * 64,
              _speedups.STAMPS: {"agentspeak.fork": _speedups.source_stamp(source) if stamp_ok else "1:2"}}
    (package / _speedups.MANIFEST).write_text(json.dumps(record))
    return package


@pytest.mark.parametrize("digest_ok, stamp_ok, stale", [
    (True, True, False),
    (True, False, False),      # touched, not edited: the digest decides
    (False, True, False),      # the stamp the build saw is trusted without hashing, as Python trusts a .pyc's
    (False, False, True),      # edited since the build
])
def test_the_start_hashes_a_source_only_when_its_size_or_time_changed(tmp_path, digest_ok, stamp_ok, stale,
                                                                        monkeypatch):
    monkeypatch.delenv(_speedups.PURE_ENV, raising=False)
    package = _fake_build(tmp_path, digest_ok, stamp_ok)
    hashed, digest = [], _speedups.source_digest
    monkeypatch.setattr(_speedups, "source_digest", lambda path: hashed.append(path) or digest(path))
    sources, stale_modules = _speedups.modules_to_load_from_source(package)
    assert stale_modules == (["agentspeak.fork"] if stale else [])
    assert bool(sources) == stale
    assert bool(hashed) == (not stamp_ok)
