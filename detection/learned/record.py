"""Recording one run: every event's metadata (time, channel, encoded numbers incl. size) and the 1 Hz
counters of every component process, written to one compressed ``.npz`` per run.

Layout of ``run-NNN.npz``: ``ticks`` (epoch s), per component ``counters/<component>`` (ticks ×
``COUNTER_NAMES``), per channel ``events/<topic>/t`` and ``events/<topic>/x`` (float32, columns in the
data set's manifest). Raw payloads are not kept: the encoded numbers are all the detector uses.
"""
from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Callable

import numpy as np

from detection.learned.counters import COUNTER_NAMES, read_counters


class RunRecorder:
    """Collects events from a tap and samples the components' processes at every whole second."""

    def __init__(self, pids: dict[str, int], clock: Callable[[], float] = time.time) -> None:
        import psutil

        self.processes = {name: psutil.Process(pid) for name, pid in pids.items()}
        self.clock = clock
        self.events: dict[str, list[tuple[float, np.ndarray]]] = {}
        self.ticks: list[float] = []
        self.counters: dict[str, list[np.ndarray]] = {name: [] for name in pids}
        self.lost: list[str] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._sample, daemon=True, name="perfbugs-counters")

    def on_event(self, t: float, topic: str, vector: np.ndarray) -> None:
        with self._lock:
            self.events.setdefault(topic, []).append((t, vector))

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
        with self._lock:
            for name, rows in self.counters.items():
                arrays[f"counters/{name}"] = np.array(rows).reshape(len(rows), len(COUNTER_NAMES))
            counts = {}
            for topic, items in self.events.items():
                items.sort(key=lambda item: item[0])
                arrays[f"events/{topic}/t"] = np.array([t for t, _ in items])
                arrays[f"events/{topic}/x"] = np.array([x for _, x in items], dtype=np.float32)
                counts[topic] = len(items)
        np.savez_compressed(path, **arrays)
        return counts
