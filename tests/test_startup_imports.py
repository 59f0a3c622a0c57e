"""Short commands import only what they use (issue 23 §1): what a run imports is most of a short run's time.

Speeds are measured by ``python -m benchmarks startup``; these tests keep the imports that made them slow
from coming back, in a fresh interpreter as a user's ``faultmas`` runs.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def _imported_by(argv: list[str], watched: tuple[str, ...], env: dict[str, str] | None = None) \
        -> tuple[int, str, list[str]]:
    """Run ``faultmas ARGV`` in a new interpreter: (exit status, its output, the ``watched`` modules it imported)."""
    code = ("import io, json, sys\n"        # not contextlib (redirect_stdout): a watched module
            "from agents.cli import main\n"
            "out = sys.stdout = io.StringIO()\n"
            "try:\n"
            f"    status = main({argv!r})\n"
            "except SystemExit as exc:\n"        # --help
            "    status = exc.code\n"
            "sys.stdout = sys.__stdout__\n"
            f"print(json.dumps([status, out.getvalue(), sorted(m for m in {watched!r} if m in sys.modules)]))\n")
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=120,
                          env=None if env is None else {**os.environ, **env})
    assert done.returncode == 0, done.stderr
    status, output, imported = json.loads(done.stdout.splitlines()[-1])
    return status, output, imported


def test_help_imports_no_sub_command_and_no_parser():
    status, output, imported = _imported_by(["--help"], ("agentspeak", "diagnosis", "agents.mas_cli", "lark", "yaml",
                                                         "psutil", "shutil"))
    assert status == 0 and "COMMAND" in output
    assert imported == []


def test_diagnosing_a_netlist_needs_neither_yaml_nor_lark_nor_psutil(tmp_path):
    bench = tmp_path / "and.bench"
    bench.write_text("INPUT(a)\nINPUT(b)\nOUTPUT(y)\ny = AND(a, b)\n")
    obs = tmp_path / "obs.json"
    obs.write_text(json.dumps({"a": 1, "b": 1, "y": 0}))
    status, output, imported = _imported_by(
        ["diagnose", str(bench), "--obs", str(obs), "--json"],
        ("yaml", "lark", "psutil", "pysat.examples.rc2", "pysat.card", "pysat.solvers",
         # each was a few % of a short diagnose: pathlib (urllib.parse...) by the compiled interpreter's guard and
         # read_source; contextlib for one context manager; the hitting-set solver and post-dominators (bounds > 3)
         "pathlib", "contextlib", "diagnosis.hitting_sets", "diagnosis.dominators"))
    assert status == 0 and json.loads(output)["diagnoses"] == [["y"]]
    assert imported == []


def test_a_yaml_model_still_reads_its_formulas(tmp_path):
    """The other side of the laziness: a YAML model imports YAML and the formula parser when it is read."""
    model = tmp_path / "lamp.yaml"
    model.write_text('system: lamp\ncomponents: [bulb]\nobservations: [powered, lit]\n'
                     'behaviour:\n  - "!AB(bulb) -> (lit <-> powered)"\n')
    obs = tmp_path / "obs.json"
    obs.write_text(json.dumps({"lit": 0, "powered": 1}))
    status, output, imported = _imported_by(["diagnose", str(model), "--obs", str(obs), "--json"], ("yaml", "lark"))
    assert (status, json.loads(output)["diagnoses"] if status == 0 else output) == (0, [["bulb"]])
    assert imported == ["lark", "yaml"]


def test_a_project_without_environment_does_not_load_the_bridge_registry(tmp_path):
    """The registry lists installed bridges through importlib.metadata: a cost only a project naming one pays."""
    (tmp_path / "hello.asl").write_text('!start.\n+!start <- .print("hello world").\n')
    (tmp_path / "hello.mas2j").write_text("MAS hello {\n    agents:\n        hello hello.asl;\n}\n")
    status, output, imported = _imported_by(["mas", "run", str(tmp_path / "hello.mas2j")],
                                            ("robot_bridge.registry", "importlib.metadata"))
    assert (status, output.strip().splitlines()[-1]) == (0, "[hello] hello world")
    assert "robot_bridge.registry" not in imported


def test_a_sub_commands_help_imports_no_shutil():
    """argparse's formatter imports shutil for the terminal width, in every sub-command's parser too."""
    status, output, imported = _imported_by(["diagnose", "--help"], ("shutil",))
    assert status == 0 and "--max-card" in output
    assert imported == []


def test_a_projects_option_literals_come_from_the_parse_cache_when_run_again(tmp_path):
    """``beliefs=`` options are parsed once: run again, the project imports neither Lark nor the parser."""
    (tmp_path / "ring.asl").write_text("!go.\n+!go : next(N) <- .print(N).\n")
    (tmp_path / "ring.mas2j").write_text('MAS ring {\n    agents:\n        a ring.asl [beliefs="next(b)"];\n'
                                         '        b ring.asl [beliefs="next(a)"];\n}\n')
    env = {"FAULTMAS_CACHE_DIR": str(tmp_path / "cache")}
    runs = [_imported_by(["mas", "run", str(tmp_path / "ring.mas2j")], ("lark", "agentspeak.parser"), env)
            for _ in range(2)]
    for status, output, _ in runs:
        assert status == 0 and sorted(output.split()) == ["[a]", "[b]", "a", "b"]
    assert runs[0][2] == ["agentspeak.parser", "lark"] and runs[1][2] == []
