"""The targets: a component process's resource counters, read with psutil once a second.

Levels (RSS, VMS, threads, open fds) are used as they are; cumulative counters (CPU time, context
switches, IO bytes, page faults) as their increase over the last tick. Page faults are not in psutil:
they come from ``/proc/PID/stat`` (minor + major), 0 where there is no such file.
"""
from __future__ import annotations

import numpy as np

COUNTER_NAMES: tuple[str, ...] = ("cpu_s", "rss_mb", "vms_mb", "threads", "fds", "ctx_switches",
                                  "io_bytes", "page_faults")
CUMULATIVE = {"cpu_s", "ctx_switches", "io_bytes", "page_faults"}
TARGET_NAMES: tuple[str, ...] = tuple(f"d_{n}" if n in CUMULATIVE else n for n in COUNTER_NAMES)


def _page_faults(pid: int) -> float:
    try:
        with open(f"/proc/{pid}/stat", "rb") as stat:
            fields = stat.read().rsplit(b")", 1)[1].split()
        return float(int(fields[7]) + int(fields[9]))        # minflt, majflt (fields 10 and 12)
    except (OSError, IndexError, ValueError):
        return 0.0


def read_counters(process) -> np.ndarray:
    """One sample of ``COUNTER_NAMES`` for a ``psutil.Process`` (raises ``psutil.Error`` if it is gone)."""
    with process.oneshot():
        cpu = process.cpu_times()
        memory = process.memory_info()
        ctx = process.num_ctx_switches()
        try:
            io = process.io_counters()
            io_bytes = float(io.read_chars + io.write_chars)
        except (AttributeError, OSError):
            io_bytes = 0.0
        return np.array([cpu.user + cpu.system, memory.rss / 2**20, memory.vms / 2**20,
                         process.num_threads(), process.num_fds(), ctx.voluntary + ctx.involuntary,
                         io_bytes, _page_faults(process.pid)], dtype=np.float64)


def targets_from_counters(samples: np.ndarray) -> np.ndarray:
    """Targets at each sample after the first: levels as they are, cumulative counters differenced."""
    samples = np.asarray(samples, dtype=np.float64)
    out = samples[1:].copy()
    for i, name in enumerate(COUNTER_NAMES):
        if name in CUMULATIVE:
            out[:, i] = np.diff(samples[:, i])
    return out
