"""Netlists kept between runs (diagnosis/netlist_cache.py, issue 23 §1): a .bench file diagnosed again unchanged is
not parsed and encoded again; anything the model depends on makes the entry miss; nothing here is needed."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from agentspeak.errors import SourceError
from diagnosis import netlist_cache
from diagnosis.bench import load_bench_model
from diagnosis.engine import Diagnoser
from diagnosis.loader import load_model
from diagnosis.model import SystemModel

OBS = {"G1gat": True, "G2gat": True, "G3gat": True, "G6gat": True, "G7gat": True, "G22gat": True, "G23gat": True}


@pytest.fixture
def cache(tmp_path: Path, monkeypatch) -> Path:
    where = tmp_path / "cache"
    monkeypatch.setenv("FAULTMAS_CACHE_DIR", str(where))
    return where / netlist_cache.SUBDIRECTORY


@pytest.fixture
def c17(tmp_path: Path, data_dir: Path) -> Path:
    copy = tmp_path / "c17.bench"
    copy.write_text((data_dir / "c17.bench").read_text())
    return copy


def _parses(monkeypatch) -> list[str]:
    """Records every parse of a .bench file from now on."""
    import diagnosis.bench as bench

    calls: list[str] = []
    original = bench.parse_bench
    monkeypatch.setattr(bench, "parse_bench", lambda path, text=None: calls.append(str(path)) or original(path, text))
    return calls


def test_a_netlist_read_again_comes_from_the_cache_and_diagnoses_the_same(cache, c17, monkeypatch) -> None:
    parses = _parses(monkeypatch)
    first = load_model(c17)
    again = load_model(c17)
    assert parses == [str(c17)] and len(list(cache.iterdir())) == 1
    assert again == first == load_bench_model(c17) and again is not first
    assert again.simulation is not None          # the compiled simulation is kept too
    answer = Diagnoser(first).diagnose(OBS, max_card=3).diagnoses
    assert answer and Diagnoser(again).diagnose(OBS, max_card=3).diagnoses == answer


def test_an_edited_file_or_other_code_misses(cache, c17, monkeypatch) -> None:
    parses = _parses(monkeypatch)
    load_model(c17)
    c17.write_text(c17.read_text().replace("G22gat = nand(G10gat, G16gat)", "G22gat = and(G10gat, G16gat)"))
    edited = load_model(c17)
    assert len(parses) == 2 and [g for g in edited.gates if g[0] == "G22gat"][0][1] == "and"
    monkeypatch.setattr(netlist_cache, "_code_key", ("another diagnosis package",))
    load_model(c17)
    assert len(parses) == 3
    load_model(c17)
    assert len(parses) == 3


def test_the_code_key_changes_when_a_diagnosis_module_changes(tmp_path: Path) -> None:
    from agentspeak.user_cache import code_files

    package = tmp_path / "diagnosis"
    package.mkdir()
    (package / "bench.py").write_text("GATE_TYPES = ()\n")
    before = code_files(str(package))
    (package / "bench.py").write_text("GATE_TYPES = ('and',)\n")
    assert code_files(str(package)) != before


def test_a_damaged_entry_or_an_unwritable_directory_only_costs_the_parse(cache, c17, monkeypatch, tmp_path) -> None:
    parses = _parses(monkeypatch)
    load_model(c17)
    [entry] = cache.iterdir()
    entry.write_bytes(entry.read_bytes()[:-7])
    assert isinstance(load_model(c17), SystemModel) and len(parses) == 2
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setenv("FAULTMAS_CACHE_DIR", str(blocker))
    assert isinstance(load_model(c17), SystemModel) and len(parses) == 3


def test_a_bad_netlist_is_reported_each_time_and_never_kept(cache, tmp_path: Path) -> None:
    bad = tmp_path / "bad.bench"
    bad.write_text("INPUT(a)\nOUTPUT(b)\nb = FOO(a)\n")
    for _ in range(2):
        with pytest.raises(SourceError, match=r"bad.bench:3: unknown gate type 'FOO'"):
            load_model(bad)
    bad.write_bytes(b"INPUT(a)\n# caf\xe9\n")
    with pytest.raises(SourceError, match=r"bad.bench:2:6: this netlist is not UTF-8"):
        load_model(bad)
    assert not cache.exists() or not list(cache.iterdir())


def test_a_cached_diagnose_run_imports_neither_the_parser_nor_pysat_solvers(cache, c17, tmp_path: Path) -> None:
    """What the cache and diagnosis/sat.py are for (issue 23): the second run of ``faultmas diagnose`` on a netlist
    loads no netlist reader, no pysat.solvers/pysat.formula, no logging, dataclasses or typing (bounds above 3 and
    --min-card-only use python-sat's cardinality encodings and RC2, which import pysat.formula)."""
    obs = tmp_path / "obs.json"
    obs.write_text(json.dumps({k: int(v) for k, v in OBS.items()}))
    code = ("import sys\nfrom agents.cli import main\n"
            f"assert main(['diagnose', {str(c17)!r}, '--obs', {str(obs)!r}, '--max-card', '3', '--json']) == 0\n"
            "print(sorted(m for m in ('diagnosis.bench', 'diagnosis.builder', 'pysat.solvers', 'pysat.formula', "
            "'logging', 'dataclasses', 'typing', 'lark') if m in sys.modules))")
    runs = [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
            for _ in range(2)]
    assert all(run.returncode == 0 for run in runs), runs[-1].stderr
    first, second = (run.stdout.strip().splitlines() for run in runs)
    assert json.loads(first[0])["diagnoses"] == json.loads(second[0])["diagnoses"]
    assert first[-1] == "['diagnosis.bench', 'diagnosis.builder']"       # read and encoded once ...
    assert second[-1] == "[]"                                             # ... then from the cache
