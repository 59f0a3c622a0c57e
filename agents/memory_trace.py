"""What an agent process keeps, for finding a leak (issue 22): off unless ``FAULTMAS_MEMTRACE_DIR`` is set.

A soak showed the agent processes growing by a few MiB an hour in Python's own memory; RSS and its parts say
how much, not what. With ``FAULTMAS_MEMTRACE_DIR=DIR`` in its environment (``faultmas run`` and the soak pass
theirs on to the agents), each ``faultmas agent run`` starts ``tracemalloc`` (``FAULTMAS_MEMTRACE_FRAMES``
frames a traceback, default 8) and writes, every ``FAULTMAS_MEMTRACE_EVERY`` wall seconds (default 120) and
whenever it gets SIGUSR1, a snapshot ``DIR/NAME-NNN.tracemalloc`` and a census of its live objects by type
``DIR/NAME-NNN.census.json``. With ``FAULTMAS_MEMTRACE_FRAMES=0`` there is no tracemalloc (it costs memory and time of its own), only the
censuses, which also carry pymalloc's own account. ``python -m agents.memory_trace DIR NAME`` then says what grew between the
second snapshot and the last (the first is taken while the agent is still loading): the tracebacks whose
memory grew most and the object types whose count did. tracemalloc slows the agent and costs memory of its
own, so this is for a diagnostic run, never the default. The census holds this process's simulated worlds still
while it runs (``gc.get_objects`` beside the simulator's camera detector failed its OpenCV calls, issue 22)."""
from __future__ import annotations

import argparse
import collections
import contextlib
import gc
import json
import logging
import os
import signal
import sys
import threading
import tracemalloc
from pathlib import Path
from typing import Callable

ENV_DIR = "FAULTMAS_MEMTRACE_DIR"
ENV_EVERY = "FAULTMAS_MEMTRACE_EVERY"
ENV_FRAMES = "FAULTMAS_MEMTRACE_FRAMES"
ENV_HOLDERS = "FAULTMAS_MEMTRACE_HOLDERS"
ENV_COLLECT = "FAULTMAS_MEMTRACE_COLLECT"


def census() -> dict[str, int]:
    """Live gc-tracked objects by type (module-qualified name)."""
    return dict(collections.Counter(f"{type(o).__module__}.{type(o).__qualname__}" for o in gc.get_objects()))


_PYMALLOC_FIELDS = {"# arenas allocated current": "arenas", "# arenas highwater mark": "arenas_highwater",
                    "# bytes in allocated blocks": "in_use", "# bytes in available blocks": "free_blocks",
                    "# bytes lost to quantization": "quantization", "Total": "total"}


def pymalloc_stats() -> dict[str, float]:
    """Python's small-object allocator's own account (``sys._debugmallocstats``, which only writes to the C
    stderr, read through a temporary file): its arenas (1 MiB each), the bytes of blocks in use, of free
    blocks in its pools, and the tuples kept on the free lists: what tells objects that are kept from pages
    that are only fragmented. Lines others write to stderr meanwhile (a few ms) land in the file and are
    copied back."""
    import tempfile

    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile(mode="w+") as captured:
        try:
            os.dup2(captured.fileno(), 2)
            sys._debugmallocstats()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        captured.seek(0)
        text = captured.read()
    stats: dict[str, float] = {"free_tuples": 0}
    kept_out = []
    for line in text.splitlines():
        head, _, value = line.partition("=")
        name = _PYMALLOC_FIELDS.get(head.strip())
        if name is not None and name not in stats:     # the first "Total" is the arenas'
            stats[name] = int(value.replace(",", "").strip())
        elif "-sized PyTupleObjects" in line:
            stats["free_tuples"] += int(line.split()[0])
        elif "unused pools" in line:
            stats["unused_pools"] = int(value.replace(",", "").strip())
        elif not ("=" in line or line.startswith((" ", "class", "-----", "arena map")) or not line.strip()):
            kept_out.append(line)     # another thread's line
    if kept_out:
        print("\n".join(kept_out), file=sys.stderr)
    return {k: round(v / 2 ** 20, 2) if k not in ("arenas", "arenas_highwater", "free_tuples") else v
            for k, v in stats.items()}


def holders(lines: list[tuple[str, int]], samples: int = 5) -> dict[str, dict]:
    """For each ``(file suffix, line)``: the objects still alive that were allocated there, counted by type and
    by the type of what refers to them, with a few referrers shown: what a growing line of ``growth`` is kept
    by. Walks every gc object's referents, so atomic objects (str, float) held by a container are found too."""
    wanted = {(suffix, line): {"objects": collections.Counter(), "held_by": collections.Counter(), "samples": []}
              for suffix, line in lines}
    def pairs():
        for holder in gc.get_objects():
            for obj in gc.get_referents(holder):
                yield holder, obj
                if type(obj) in (dict, tuple) and not gc.is_tracked(obj):   # untracked: atoms only, not listed
                    for atom in gc.get_referents(obj):
                        yield obj, atom
    for holder, obj in pairs():
        traceback = tracemalloc.get_object_traceback(obj)
        if not traceback:
            continue
        frame = traceback[-1]    # the most recent frame is the last one
        for (suffix, line), found in wanted.items():
            if frame.lineno == line and frame.filename.endswith(suffix):
                found["objects"][type(obj).__qualname__] += 1
                found["held_by"][type(holder).__qualname__] += 1
                if len(found["samples"]) < samples:
                    found["samples"].append(f"{type(obj).__qualname__} {repr(obj)[:60]} in "
                                            f"{type(holder).__qualname__} {repr(holder)[:160]}")
    return {f"{suffix}:{line}": {"objects": dict(f["objects"]), "held_by": dict(f["held_by"].most_common(10)),
                                 "samples": f["samples"]} for (suffix, line), f in wanted.items()}


def _lines(spec: str) -> list[tuple[str, int]]:
    """``"wire.py:168,agent.py:1012"`` -> [("wire.py", 168), ("agent.py", 1012)]."""
    return [(part.rpartition(":")[0], int(part.rpartition(":")[2])) for part in spec.split(",") if part.strip()]


class MemoryTrace:
    """Snapshots of one agent process's Python memory, written to ``directory`` every ``every`` seconds and
    on ``take()`` (SIGUSR1)."""

    def __init__(self, directory: str | os.PathLike, name: str, every: float = 120.0, frames: int = 8,
                 holdings: Callable[[], dict] | None = None) -> None:
        self.directory, self.name, self.every, self.frames = Path(directory), name, every, frames
        self.holdings = holdings
        self.count = 0
        self._wake = threading.Event()
        self._stopped = threading.Event()
        self._thread = threading.Thread(target=self._loop, name=f"memtrace-{name}", daemon=True)

    def start(self) -> MemoryTrace:
        self.directory.mkdir(parents=True, exist_ok=True)
        if self.frames > 0 and not tracemalloc.is_tracing():
            tracemalloc.start(self.frames)
        self._thread.start()
        return self

    def take(self) -> None:
        """Ask for a snapshot now (safe in a signal handler: only sets an event)."""
        self._wake.set()

    def stop(self) -> None:
        """A last snapshot, then no more."""
        self._stopped.set()
        self._wake.set()
        self._thread.join(timeout=60)

    def _loop(self) -> None:
        from robot_bridge.failure_log import FailureLog

        failures = FailureLog(logging.getLogger(__name__), f"memory trace of {self.name}: a snapshot")   # a full
        while True:                                                            # disk costs snapshots, not the trace
            self._wake.wait(self.every)
            self._wake.clear()
            with failures.contained(f"number {self.count}"):
                self.write()
            if self._stopped.is_set():
                return

    def write(self) -> Path:
        """One snapshot and census, numbered; returns the snapshot's path."""
        stem = self.directory / f"{self.name}-{self.count:03d}"
        self.count += 1
        if tracemalloc.is_tracing():
            tracemalloc.take_snapshot().dump(f"{stem}.tracemalloc")
        with _worlds_still():
            kept = {"types": census(), "pymalloc": pymalloc_stats(), "gc_stats": gc.get_stats()}
            if os.environ.get(ENV_COLLECT):      # how much of it was garbage in cycles, waiting for a full collection
                kept["collected"] = gc.collect()
                kept["types_after_collect"] = census()
            if os.environ.get(ENV_HOLDERS):
                kept["holders"] = holders(_lines(os.environ[ENV_HOLDERS]))
        if self.holdings is not None:
            try:
                kept["holdings"] = self.holdings()
            except Exception as exc:     # read from another thread while the agent runs: a diagnostic, never fatal
                kept["holdings"] = {"error": repr(exc)}
        stem.with_suffix(".census.json").write_text(json.dumps(kept))
        return stem.with_suffix(".tracemalloc")


def _worlds_still():
    """The simulated worlds of this process held still while the census runs (a no-op without a simulator).

    ``gc.get_objects`` hands out every object under construction too: a census beside the simulator's thread took
    the tuple ``cv2.findContours`` was filling with the GIL released, and OpenCV failed that camera frame with
    ``SystemError: ... tupleobject.c: bad argument to internal function`` (issue 22; docs/reliability.md). Other C
    extensions that release the GIL while filling a new tuple can fail the same way: the trace is a diagnostic
    switch, never on by default."""
    runner = sys.modules.get("robot_bridge.sim.runner")     # loaded only where a world runs: no import for it
    return runner.all_paused() if runner is not None else contextlib.nullcontext()


def agent_holdings(runtime) -> dict:
    """How many items each structure of each agent of ``runtime`` holds that could grow with the conversations
    and tasks it has been through (what a leak would show in: compare two censuses)."""
    held = {}
    for name, agent in list(runtime.agents.items()):
        buckets = list(agent.bb._facts.values())
        held[name] = {"beliefs": agent.bb.size, "belief_buckets": len(buckets),
                      "first_arg_index_keys": sum(len(b.by_arg) for b in buckets),
                      "sorted_by_first_arg": sum(len(b._sorted_by_arg) for b in buckets),
                      "timers": len(agent.timers), "pending_asks": len(agent.pending_asks),
                      "suspended": len(agent.suspended), "running": len(agent.running),
                      "events": len(agent.events), "event_waiters": len(agent.event_waiters),
                      "condition_waiters": len(agent.condition_waiters), "percepts": len(agent.percepts),
                      "plans": len(agent.plans.plans), "dropped": dict(agent.dropped),
                      "pending_futures": agent.pending_futures}
    from agentspeak.solver import _COMPILED
    held["compiled_formulas"] = len(_COMPILED)
    from agents.zenoh_arch import CONTENT_CACHE
    texts = list(CONTENT_CACHE._terms)
    held["content_cache"] = {"entries": len(texts), "text_bytes": CONTENT_CACHE._bytes, "newest": texts[-5:]}
    return held


def start_from_environment(name: str, holdings: Callable[[], dict] | None = None) -> MemoryTrace | None:
    """The trace ``FAULTMAS_MEMTRACE_DIR`` asks for (SIGUSR1 takes a snapshot), or None when it is not set.
    ``holdings()``: the sizes of what the process holds, written with each census."""
    directory = os.environ.get(ENV_DIR)
    if not directory:
        return None
    trace = MemoryTrace(directory, name, float(os.environ.get(ENV_EVERY, "120")),
                        int(os.environ.get(ENV_FRAMES, "8")), holdings).start()
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGUSR1, lambda *_: trace.take())
    return trace


def growth(directory: str | os.PathLike, name: str, first: int = 1, last: int | None = None,
           top: int = 25) -> str:
    """What grew in agent ``name``'s snapshots from number ``first`` to ``last`` (default: the last written)."""
    directory = Path(directory)
    snapshots = sorted(directory.glob(f"{name}-[0-9][0-9][0-9].tracemalloc"))
    if len(snapshots) < 2:
        raise ValueError(f"{directory}: fewer than two snapshots of {name}")
    last = len(snapshots) - 1 if last is None else last
    first = min(first, last - 1)
    a, b = (tracemalloc.Snapshot.load(str(snapshots[i])) for i in (first, last))
    ignore = [tracemalloc.Filter(False, tracemalloc.__file__)]
    a, b = a.filter_traces(ignore), b.filter_traces(ignore)
    lines = [f"{name}: {snapshots[first].name} -> {snapshots[last].name}, "
             f"traced {sum(s.size for s in a.statistics('filename')) / 2 ** 20:.2f} -> "
             f"{sum(s.size for s in b.statistics('filename')) / 2 ** 20:.2f} MiB", "", "top growth by line:"]
    for stat in b.compare_to(a, "lineno")[:top]:
        lines.append(f"  {stat.size_diff / 1024:+9.1f} KiB {stat.count_diff:+7d} blocks  {stat.traceback[0]}")
    lines += ["", "top growth by traceback:"]
    for stat in b.compare_to(a, "traceback")[:max(3, top // 3)]:
        lines.append(f"  {stat.size_diff / 1024:+9.1f} KiB {stat.count_diff:+7d} blocks")
        lines += [f"    {line}" for line in stat.traceback.format(most_recent_first=True)]
    kept_a, kept_b = (json.loads(snapshots[i].with_suffix(".census.json").read_text()) for i in (first, last))
    census_a, census_b = kept_a["types"], kept_b["types"]
    grown = sorted(((census_b.get(t, 0) - census_a.get(t, 0), t) for t in set(census_a) | set(census_b)),
                   reverse=True)
    lines += ["", "object types grown:"] + [f"  {n:+7d} {t}" for n, t in grown[:top] if n > 0]
    if "holdings" in kept_b:
        lines += ["", "holdings (first -> last):"]
        lines += [f"  {json.dumps(kept_a.get('holdings'))}", f"  {json.dumps(kept_b['holdings'])}"]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="what an agent's Python memory grew by, between two snapshots "
                                                 f"written with {ENV_DIR}")
    parser.add_argument("directory")
    parser.add_argument("name", help="the agent's name")
    parser.add_argument("--first", type=int, default=1, help="snapshot number to compare from (default 1)")
    parser.add_argument("--last", type=int, default=None, help="snapshot number to compare to (default: the last)")
    parser.add_argument("--top", type=int, default=25)
    args = parser.parse_args(argv)
    try:
        print(growth(args.directory, args.name, args.first, args.last, args.top))
    except (OSError, ValueError) as exc:
        print(f"agents.memory_trace: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
