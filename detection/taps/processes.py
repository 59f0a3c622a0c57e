"""psutil samples of the processes the ``resource`` observers watch: CPU % of one core and RSS in MB.

A process is found by its name or a fragment of its command line (the first match, cached while it
lives); a process that is not (or no longer) there gives no sample.
"""
from __future__ import annotations

import psutil


class ProcessSampler:
    def __init__(self, patterns: dict[str, str]) -> None:
        self.patterns = dict(patterns)          # node -> name or command-line fragment
        self._procs: dict[str, psutil.Process] = {}

    def _find(self, pattern: str) -> psutil.Process | None:
        me = psutil.Process().pid
        for proc in psutil.process_iter(["name", "cmdline"]):
            if proc.pid == me:
                continue
            cmdline = " ".join(proc.info.get("cmdline") or ())
            if proc.info.get("name") == pattern or pattern in cmdline:
                proc.cpu_percent(None)          # the first call starts the measurement
                return proc
        return None

    def sample(self) -> dict[str, dict[str, float]]:
        out = {}
        for node, pattern in self.patterns.items():
            proc = self._procs.get(node)
            if proc is None or not proc.is_running():
                proc = self._find(pattern)
                if proc is None:
                    self._procs.pop(node, None)
                    continue
                self._procs[node] = proc
                continue                        # a CPU share needs two readings
            try:
                with proc.oneshot():
                    out[node] = {"cpu": proc.cpu_percent(None), "memory": proc.memory_info().rss / 1e6}
            except psutil.Error:
                self._procs.pop(node, None)
        return out
