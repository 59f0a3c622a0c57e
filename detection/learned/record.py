"""Recording one run: every event's metadata (time, channel, encoded numbers incl. size) and the 1 Hz
counters of every component process, written to one compressed ``.npz`` per run.

Layout of ``run-NNN.npz``: ``ticks`` (epoch s), per component ``counters/<component>`` (ticks ×
``COUNTER_NAMES``), per channel ``events/<topic>/us`` (int64 µs since ``ticks[0]`` − 10 s: small
integers, which compress) and ``events/<topic>/x`` (float32, columns in the data set's manifest).
Raw payloads are not kept: the encoded numbers are all the detector uses. A JSON channel (a Zenoh key,
``on_json``) gets its columns when the run is saved: the size, then every path seen on it, sorted
(``json_columns``; the manifest lists them per run, ``dataset`` aligns runs that saw different paths). To keep the paper data set
under 30 MB the numbers keep 12 significant bits (``quantise``: relative error < 2^-11 ≈ 4.9e-4, far below
the simulated sensors' noise, and a window mean of them is as good) and the zip members are LZMA
(numpy reads them as any ``.npz``): a minute of the team is ~210 kB instead of ~390 kB.
"""
from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Callable

import numpy as np

from detection.learned.counters import COUNTER_NAMES, read_counters
from detection.learned.encoding import json_columns, vector_of

TIME_ORIGIN_BEFORE_S = 10.0
"""Event times are stored relative to this long before the first tick (events precede it)."""


SIGNIFICANT_BITS = 12


def quantise(values: np.ndarray, bits: int = SIGNIFICANT_BITS) -> np.ndarray:
    """float32 ``values`` with only ``bits`` significant bits (the low mantissa bits zeroed: they
    are noise to the detector, and incompressible)."""
    raw = np.ascontiguousarray(values, dtype=np.float32).view(np.uint32)
    return (raw & np.uint32((0xFFFFFFFF << (24 - bits)) & 0xFFFFFFFF)).view(np.float32)


def event_times(arrays, topic: str) -> np.ndarray | None:
    """The epoch times of ``topic``'s events in a run file's arrays (None: no event)."""
    if f"events/{topic}/us" in arrays:
        return arrays[f"events/{topic}/us"] / 1e6 + (float(arrays["ticks"][0]) - TIME_ORIGIN_BEFORE_S)
    return arrays.get(f"events/{topic}/t")


def save_arrays(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """``np.savez`` with LZMA members (``np.load`` reads them)."""
    import zipfile
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_LZMA) as archive:
        for name, array in arrays.items():
            with archive.open(f"{name}.npy", "w", force_zip64=True) as member:
                np.lib.format.write_array(member, np.asanyarray(array), allow_pickle=False)


class RunRecorder:
    """Collects events from a tap and samples the components' processes at every whole second."""

    def __init__(self, pids: dict[str, int], clock: Callable[[], float] = time.time) -> None:
        import psutil

        self.processes = {name: psutil.Process(pid) for name, pid in pids.items()}
        self.clock = clock
        self.events: dict[str, list[tuple[float, np.ndarray]]] = {}
        self.json_events: dict[str, list[tuple[float, int, dict[str, float]]]] = {}
        self.columns: dict[str, list[str]] = {}
        """The columns of each JSON channel, known once the run is saved."""
        self.ticks: list[float] = []
        self.counters: dict[str, list[np.ndarray]] = {name: [] for name in pids}
        self.lost: list[str] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._sample, daemon=True, name="perfbugs-counters")

    def on_event(self, t: float, topic: str, vector: np.ndarray) -> None:
        with self._lock:
            self.events.setdefault(topic, []).append((t, vector))

    def on_json(self, t: float, channel: str, size: int, flat: dict[str, float]) -> None:
        """A JSON value (``encoding.flatten_json``) of ``size`` bytes on ``channel``."""
        with self._lock:
            self.json_events.setdefault(channel, []).append((t, size, flat))

    def start(self) -> "RunRecorder":
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)

    def _sample(self) -> None:
        import psutil

        while not self._stop.wait(1.0 - (self.clock() % 1.0)):
            tick = self.clock()
            row = {}
            for name, process in self.processes.items():
                try:
                    if process.status() == psutil.STATUS_ZOMBIE:     # ended, not yet reaped: its counters
                        raise psutil.ZombieProcess(process.pid)      # read 0, which is no measurement
                    row[name] = read_counters(process)
                except psutil.Error:
                    row[name] = np.full(len(COUNTER_NAMES), np.nan)
                    if name not in self.lost:
                        self.lost.append(name)
            with self._lock:
                self.ticks.append(tick)
                for name, sample in row.items():
                    self.counters[name].append(sample)

    def save(self, path: Path) -> dict[str, int]:
        """Write the run; returns the number of events per channel."""
        arrays: dict[str, np.ndarray] = {"ticks": np.array(self.ticks)}
        origin = (self.ticks[0] if self.ticks else 0.0) - TIME_ORIGIN_BEFORE_S
        with self._lock:
            for channel, items in self.json_events.items():
                columns = json_columns({key for _, _, flat in items for key in flat})
                index = {c: i for i, c in enumerate(columns)}
                self.columns[channel] = columns
                self.events[channel] = [(t, vector_of(size, flat, index)) for t, size, flat in items]
            self.json_events = {}
            for name, rows in self.counters.items():
                arrays[f"counters/{name}"] = np.array(rows).reshape(len(rows), len(COUNTER_NAMES))
            counts = {}
            for topic, items in self.events.items():
                items.sort(key=lambda item: item[0])
                arrays[f"events/{topic}/us"] = np.round((np.array([t for t, _ in items]) - origin) * 1e6).astype(np.int64)
                arrays[f"events/{topic}/x"] = quantise(np.array([x for _, x in items], dtype=np.float32))
                counts[topic] = len(items)
        save_arrays(path, arrays)
        return counts
