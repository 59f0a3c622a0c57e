"""What a process's resident memory is made of, cheaply enough to record once a soak task (issue 22): so a step
of RSS with no Python object behind it is explained by the soak's own rows, not guessed at afterwards.

From ``/proc/PID/smaps`` (one pass, a few milliseconds): resident MiB of the main malloc heap (``[heap]``), of
glibc's other arenas (anonymous read-write mappings starting on a 64 MiB boundary: glibc reserves each
thread arena's heap that way), of other anonymous mappings (large blocks malloc maps on their own, Python's
object arenas, Zenoh's Rust side, thread stacks), of file-backed mappings (code, shared libraries), and how
much of it is transparent huge pages (``AnonHugePages``) and lies in ranges advised for them
(``MADV_HUGEPAGE``: numpy advises every array of 4 MiB or more). psutil's ``memory_maps`` reads the same file
but keeps neither ``AnonHugePages`` nor the advice flags, the two that tell a huge-page fill from an
allocation, so the file is read here. Beside it, glibc's own account (``allocator.malloc_stats``): in use
versus freed but kept."""
from __future__ import annotations

_ARENA_ALIGN = 64 * 2 ** 20        # glibc's HEAP_MAX_SIZE on 64-bit: a thread arena's heap starts on it
_KIB = 1024


def smaps_breakdown(pid: int | str = "self") -> dict[str, float]:
    """Resident MiB of process ``pid`` by kind of mapping (``heap``, ``arenas``, ``anon``, ``file``,
    ``other``: stacks, vdso) which add up to ``rss``; ``huge``: of it, transparent huge pages; ``advised``:
    resident in ranges advised ``MADV_HUGEPAGE`` (where khugepaged may later fill a 2 MiB page in whole);
    ``arena_count``: glibc's thread arenas."""
    kib = {"heap": 0, "arenas": 0, "anon": 0, "file": 0, "other": 0, "huge": 0, "advised": 0}
    arenas = 0
    kind, rss = "other", 0
    with open(f"/proc/{pid}/smaps") as smaps:
        for line in smaps:
            head = line.split(None, 5)
            if "-" in head[0] and len(head) >= 5:       # a mapping's header: range perms offset dev inode [path]
                start = int(head[0].split("-")[0], 16)
                path = head[5].strip() if len(head) > 5 else ""
                if path == "[heap]":
                    kind = "heap"
                elif path.startswith("/"):
                    kind = "file"
                elif path:
                    kind = "other"
                elif head[1].startswith("rw") and start % _ARENA_ALIGN == 0:
                    kind, arenas = "arenas", arenas + 1
                else:
                    kind = "anon"
            elif head[0] == "Rss:":
                rss = int(head[1])
                kib[kind] += rss
            elif head[0] == "AnonHugePages:":
                kib["huge"] += int(head[1])
            elif head[0] == "VmFlags:" and "hg" in line.split()[1:]:
                kib["advised"] += rss
    breakdown = {k: round(v / _KIB, 1) for k, v in kib.items()}
    breakdown["rss"] = round(sum(kib[k] for k in ("heap", "arenas", "anon", "file", "other")) / _KIB, 1)
    breakdown["arena_count"] = arenas
    return breakdown


def memory_breakdown(pid: int | str = "self") -> dict:
    """``smaps_breakdown`` and, for this process, glibc's account of its heaps under ``malloc`` (MiB)."""
    from robot_bridge.sim.allocator import malloc_stats

    breakdown: dict = smaps_breakdown(pid)
    if pid == "self":
        breakdown["malloc"] = malloc_stats()
    return breakdown
