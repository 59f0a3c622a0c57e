"""setup.py, the build of the optional compiled parts: a module the C compiler fails on is left out (the
build goes on, that module's source is used), and nothing an earlier build made is kept in its place.

Runs the real build in a copy of the tree, with the last build's C files and compiled files copied along
(so only the edited sources are translated again) and a C compiler that does not exist."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from agentspeak import _speedups

REPO = Path(__file__).resolve().parents[1]
BUILD = REPO / "build"
BUILT = (REPO / "agentspeak" / _speedups.MANIFEST).exists() and (BUILD / "cython").is_dir() \
    and any(BUILD.glob("lib.*"))


def _copy_of_the_tree(tmp_path: Path) -> Path:
    copy = tmp_path / "tree"
    skip = shutil.ignore_patterns("__pycache__")
    for name in ("setup.py", "pyproject.toml", "README.md", "LICENSE", "robot_bridge/__init__.py"):
        (copy / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(REPO / name, copy / name)
    for name in ("agentspeak", "robot_bridge/sim", "build/cython", *(str(p.relative_to(REPO)) for p in BUILD.glob("lib.*"))):
        shutil.copytree(REPO / name, copy / name, ignore=skip)    # copy2: times kept, so up-to-date stays so
    return copy


@pytest.mark.timeout(300)
@pytest.mark.skipif(not BUILT, reason="the compiled parts are not built here (make speedups)")
def test_a_module_the_compiler_fails_on_is_left_out_and_runs_from_source(tmp_path):
    copy = _copy_of_the_tree(tmp_path)
    for edited in (copy / "agentspeak" / "copier.py", copy / "robot_bridge" / "sim" / "_zbuffer.pyx"):
        edited.write_text(edited.read_text() + "\n# edited after the build\n")
    env = {k: v for k, v in os.environ.items() if k != _speedups.PURE_ENV}
    env["CC"] = str(tmp_path / "no-such-compiler")
    done = subprocess.run([sys.executable, "setup.py", "build_ext", "--inplace"], cwd=copy, env=env,
                          capture_output=True, text=True, timeout=280)
    output = done.stdout + done.stderr
    assert done.returncode == 0, output[-3000:]                # optional: the build goes on
    assert 'building extension "agentspeak.copier" failed' in output
    manifest = json.loads((copy / "agentspeak" / _speedups.MANIFEST).read_text())
    assert "agentspeak.copier" not in manifest and "agentspeak.unify" in manifest
    compiled = _speedups.compiled_files(copy / "agentspeak")
    assert "agentspeak.copier" not in compiled, "an older build's file was left in the tree"
    assert "agentspeak.unify" in compiled
    assert not list((copy / "robot_bridge" / "sim").glob("_zbuffer.*.so"))   # the camera draws with numpy

    env = {**env, "PYTHONPATH": str(copy)}
    done = subprocess.run([sys.executable, "-c", "import agentspeak.copier as m; print(m.__file__)"], cwd=copy,
                          env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == str(copy / "agentspeak" / "copier.py")
    assert "agentspeak.copier" in done.stderr and "make speedups" in done.stderr
