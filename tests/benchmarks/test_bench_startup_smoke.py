"""The start-up benchmark's parts that can rot silently: the plain python-sat baseline must find the same
diagnoses as faultmas (or the whole-process ratio compares different work), and a startup row must verify
the command's output. No timing is asserted (speed lives in ``python -m benchmarks startup``)."""
from __future__ import annotations

import json
import subprocess
import sys
import zlib
from pathlib import Path

import pytest

from benchmarks.bench_startup import ISCAS, Timing, _check, _timed

pytestmark = pytest.mark.skipif(not (ISCAS / "c432.bench").exists(), reason=f"{ISCAS} is missing")


@pytest.mark.parametrize("circuit", ["c17", "c432"])
def test_the_python_sat_script_finds_the_diagnoses_faultmas_finds(circuit: str, tmp_path: Path) -> None:
    from benchmarks.bench_diagnosis import make_instances
    from diagnosis.bench import netlist_model, parse_bench
    from diagnosis.engine import Diagnoser

    bench = ISCAS / f"{circuit}.bench"
    netlist = parse_bench(bench)
    (_, observations), = make_instances(netlist, 1, [2], seed=zlib.crc32(circuit.encode()))
    obs = tmp_path / "obs.json"
    obs.write_text(json.dumps({k: int(v) for k, v in observations.items()}))
    script = Path(__file__).resolve().parents[2] / "benchmarks" / "pysat_script.py"
    done = subprocess.run([sys.executable, str(script), str(bench), str(obs), "3"], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    theirs = sorted(sorted(d) for d in json.loads(done.stdout))
    ours = Diagnoser(netlist_model(netlist)).diagnose(observations, max_card=3)
    assert theirs and theirs == sorted(sorted(d) for d in ours.diagnoses)


def test_a_startup_row_fails_when_the_output_is_not_the_expected_one() -> None:
    timing = Timing()
    _check(timing, _timed(timing, [sys.executable, "-c", "print('hello')"]), "hello")
    assert timing.error == "" and timing.cell() != "FAILED"
    _check(timing, _timed(timing, [sys.executable, "-c", "print('bye')"]), "hello")
    assert "expected 'hello'" in timing.error and timing.cell() == "FAILED"


def test_the_floor_loads_the_solver_extension_and_nothing_of_faultmas_and_reads_no_file(tmp_path: Path) -> None:
    """The floor must stay what its docstring says every python-sat tool runs: were it to read the netlist or import
    faultmas, 'reachable' would no longer bound what is possible."""
    floor = Path(__file__).resolve().parents[2] / "benchmarks" / "startup_floor.py"
    done = subprocess.run([sys.executable, "-X", "importtime", str(floor), "diagnose", str(tmp_path / "missing.bench"),
                           "--obs", str(tmp_path / "missing.json"), "--max-card", "3", "--json"],
                          capture_output=True, text=True, timeout=60, cwd=tmp_path)
    assert done.returncode == 0 and done.stdout == "", done.stderr
    imported = {line.rsplit("|", 1)[-1].strip() for line in done.stderr.splitlines() if line.startswith("import time")}
    assert {"argparse", "json", "pysolvers"} <= imported
    assert not {m for m in imported if m.split(".")[0] in ("agents", "agentspeak", "diagnosis", "pysat", "shutil")}
