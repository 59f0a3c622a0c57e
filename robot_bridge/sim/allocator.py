"""Keeps a process that renders camera frames from growing run after run and hour after hour: at most
``ARENAS`` malloc arenas, and what malloc keeps freed given back now and then (``trim``, every
``TRIM_EVERY_S`` from a world's runner).

Why: glibc gives each new thread that allocates its own heap ("arena", up to 8 per core). A process that
runs world after world (``faultmas eval``, the soak of issue 22, a test session) starts new threads for
each (the world's runner, render threads, the simulator server, Zenoh's callbacks), and every frame's
colour and depth buffers (1-2 MiB, from the heap once glibc has raised its mmap threshold) left freed but
unreturned pages in whichever arena the thread had: the soak's simulator-serving process grew ~3.6 MiB per
team run with no Python object left behind. Measured (12 team worlds served in one process, 3 s each,
2026-11-25): resident anonymous memory 47 -> 125 MiB with glibc's default, 58 -> 63 MiB with 2 arenas.
Pinning the mmap threshold instead also held it flat, but cost 1.3 ms per frame in page faults; the arena
limit costs nothing measurable (the renderers hold the GIL around their allocations anyway).

A user's own ``MALLOC_ARENA_MAX`` wins; on a C library other than glibc this does nothing.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import functools
import os
import threading

ARENAS = 2
_M_ARENA_MAX = -8            # glibc's mallopt parameter (malloc.h)
_done = False
_lock = threading.Lock()


def limit_arenas(arenas: int = ARENAS) -> bool:
    """Limit this process to ``arenas`` malloc arenas (once; threads created later share them). True if set."""
    global _done
    with _lock:
        if _done:
            return False
        _done = True
        if os.environ.get("MALLOC_ARENA_MAX"):
            return False
        libc = _glibc()
        return libc is not None and libc.mallopt(_M_ARENA_MAX, arenas) == 1


TRIM_EVERY_S = 60.0
"""How often (wall seconds) a runner serving a world gives back what malloc keeps freed (``trim``)."""


def trim() -> bool:
    """Give back to the system every whole page malloc holds freed, in every arena (glibc's
    ``malloc_trim(0)``); True if some was. Why: freed memory in the middle of a heap stays resident for
    ever (only a heap's top is given back by itself), and a process that serves a world for hours frees
    camera buffers of many sizes into its two arenas: issue 22's soak held 21.5 MiB freed of its 111 MiB
    heap after half an hour (resident, nothing in use there). Milliseconds under the arenas' locks, once a
    minute: 10.7 ms to give back 9 MiB of a camera world's arena, under 0.1 ms when nothing is to be given
    back, 14-64 ms for a heap of 550 MiB two thirds freed in small pieces (the loaded 2-core machine); a page
    given back costs a page fault when used again. Does nothing on a C library other than glibc."""
    libc = _glibc()
    return libc is not None and bool(libc.malloc_trim(0))


@functools.lru_cache(maxsize=1)
def _glibc():
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.gnu_get_libc_version        # only glibc has it (and mallopt's M_ARENA_MAX)
    except (OSError, AttributeError):
        return None
    return libc


class _Mallinfo2(ctypes.Structure):
    _fields_ = [(field, ctypes.c_size_t) for field in
                ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks",
                 "keepcost")]


def malloc_stats() -> dict[str, float] | None:
    """glibc's own account of its heaps, in MiB (``mallinfo2``, glibc 2.33+), or None elsewhere: what a step of
    resident memory with no Python object behind it is made of. ``heap``: taken from the system by sbrk and
    the threads' arenas; ``mmapped``: large blocks mapped on their own; ``in_use``: allocated from the heaps
    and not freed; ``free``: freed but kept by malloc (what fragmentation holds); ``top``: of that, what lies
    at the top of the main heap. Walks every free list under the arenas' locks: a few milliseconds, once a
    task, not once a frame."""
    libc = _glibc()
    if libc is None or not hasattr(libc, "mallinfo2"):
        return None
    libc.mallinfo2.restype = _Mallinfo2
    info = libc.mallinfo2()
    mib = 2 ** 20
    return {"heap": round(info.arena / mib, 1), "mmapped": round(info.hblkhd / mib, 1),
            "in_use": round(info.uordblks / mib, 1), "free": round(info.fordblks / mib, 1),
            "top": round(info.keepcost / mib, 1)}
