"""The targets: a component process's resource counters, read with psutil once a second.

Every counter is used as its change over the last tick (1 s): CPU seconds per second, context
switches, IO bytes and page faults per second, and the growth of RSS, VMS, threads and open fds.
Why growth and not the levels: a process's RSS differs by a few hundred kB from one run to the next
(allocator, import order) while it varies by a few kB within a run; a model trained on levels
learns the run it saw, and a fresh healthy run looks like a leak (measured on the smoke data: every
tick of a held-out run flagged). Growth is ~0 in every healthy run and clearly positive under a
leak; the price is that a leak slower than the allocator's noise (~10 kB/s) goes unseen.
Page faults are not in psutil: they come from ``/proc/PID/stat`` (minor + major), 0 without that file.
"""
from __future__ import annotations

import numpy as np

COUNTER_NAMES: tuple[str, ...] = ("cpu_s", "rss_mb", "vms_mb", "threads", "fds", "ctx_switches",
                                  "io_bytes", "page_faults")
TARGET_NAMES: tuple[str, ...] = tuple(f"d_{n}" for n in COUNTER_NAMES)
RESOLUTION: tuple[float, ...] = (0.01, 4 / 1024, 4 / 1024, 1.0, 1.0, 1.0, 1.0, 1.0)
"""The smallest change each counter can show (a 10 ms CPU tick, a 4 KiB page, one thread...): a change
of that size is a measurement step, not a deviation (see ``model.fit``)."""


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
    """Targets at each sample after the first: every counter's change since the previous sample."""
    return np.diff(np.asarray(samples, dtype=np.float64), axis=0)
