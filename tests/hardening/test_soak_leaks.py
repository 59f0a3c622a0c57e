"""Found by the soak (issue 22): a long-lived process that runs MAS after MAS (``faultmas eval``, the soak
itself) kept each agent's stdout/stderr pipes and a /dev/null handle open until the garbage collector
happened to free them: the soak's open descriptors grew by ~4 per run. Now each run closes its own."""
from __future__ import annotations

import gc
import io
import os

from agentspeak.mas2j import load_mas2j
from tests.agents.distributed_fixtures import write_files


def _open_descriptors() -> int:
    return len(os.listdir("/proc/self/fd"))


def test_runs_one_after_another_leave_no_descriptors_open(tmp_path):
    from agents.distributed import run_processes

    write_files(tmp_path, {"a.asl": "!start.\n+!start <- .stopMAS.\n", "b.asl": "",
                           "m.mas2j": "MAS leaks { agents: a; b; }\n"})
    project = load_mas2j(str(tmp_path / "m.mas2j"))
    gc.disable()  # what the collector would free by chance must not hide a leak
    try:
        assert run_processes(project, timeout=120, out=io.StringIO(), err=io.StringIO()) == 0
        before = _open_descriptors()
        assert run_processes(project, timeout=120, out=io.StringIO(), err=io.StringIO()) == 0
        assert _open_descriptors() <= before, "the run left descriptors open"
    finally:
        gc.enable()
