"""The soak's account of its resident memory (tests/hardening/memory.py, issue 22): the parts add up to the
process's RSS, and memory malloc holds freed shows as freed-but-kept heap, not as memory in use: what tells a
leak from fragmentation in the soak's rows. Checked in a fresh process (nothing else allocating)."""
import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from robot_bridge.sim.allocator import _glibc

CHILD = textwrap.dedent("""
    import ctypes, json, psutil
    from tests.hardening.memory import memory_breakdown

    libc = ctypes.CDLL("libc.so.6")
    libc.malloc.restype, libc.malloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t]
    libc.free.argtypes = [ctypes.c_void_p]
    libc.malloc_trim.argtypes = [ctypes.c_size_t]
    seen = {"start": memory_breakdown(), "status_rss": psutil.Process().memory_info().rss / 2 ** 20}
    blocks = [libc.malloc(4096) for _ in range(12800)]     # 50 MiB of small blocks, from the main heap
    for block in blocks:
        ctypes.memset(block, 1, 4096)                      # touched: resident
    seen["allocated"] = memory_breakdown()
    for block in blocks[:-1]:                              # the last one keeps the heap's top: nothing trimmed
        libc.free(block)
    seen["freed"] = memory_breakdown()
    libc.malloc_trim(0)
    seen["trimmed"] = memory_breakdown()
    print(json.dumps(seen))
""")


@pytest.mark.skipif(sys.platform != "linux" or _glibc() is None, reason="/proc/PID/smaps and glibc's mallinfo2")
def test_the_breakdown_adds_up_and_tells_freed_but_kept_from_in_use():
    done = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True, timeout=120,
                          cwd=Path(__file__).resolve().parents[2])
    assert done.returncode == 0, done.stderr
    seen = json.loads(done.stdout)
    start, allocated, freed, trimmed = (seen[k] for k in ("start", "allocated", "freed", "trimmed"))

    parts = sum(start[k] for k in ("heap", "arenas", "anon", "file", "other"))
    assert abs(parts - start["rss"]) < 0.5, start
    assert abs(start["rss"] - seen["status_rss"]) < 4, (start, seen["status_rss"])   # the kernel's own count
    assert start["file"] > 1 and start["heap"] > 0, start
    assert start["malloc"] is not None, "no mallinfo2 in this glibc"

    def grew(before, after, key):
        return after[key] - before[key] if "." not in key else \
            after["malloc"][key.split(".")[1]] - before["malloc"][key.split(".")[1]]
    assert 45 < grew(start, allocated, "heap") < 60, (start, allocated)           # resident, in the heap
    assert 45 < grew(start, allocated, "malloc.in_use") < 55, (start, allocated)
    assert grew(allocated, freed, "malloc.in_use") < -45, (allocated, freed)      # freed ...
    assert grew(allocated, freed, "malloc.free") > 45, (allocated, freed)         # ... but kept by malloc
    assert grew(allocated, freed, "heap") > -5, (allocated, freed)                # and still resident
    assert grew(freed, trimmed, "heap") < -40, (freed, trimmed)                   # what malloc_trim gives back
