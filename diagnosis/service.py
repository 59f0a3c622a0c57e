"""``DiagnosisService``: what the interpreter's ``.diagnose`` / ``.possibly_faulty`` internal actions call.

The agent must keep running its other intentions while a diagnosis is computed, so every query runs on
a worker thread and returns a ``concurrent.futures.Future``; the action suspends its intention and
resumes it when the future completes. Models are cached by path and reloaded when the file changes.

From AgentSpeak to observations (``observation_of``): a literal ``moved`` is ``("moved", True)``,
``~moved`` is ``("moved", False)``, and a structured literal such as ``hz(scan)`` or ``~timing(a,b)``
is the observation named by its text without spaces (``"hz(scan)"``, ``"timing(a,b)"``).
The result for ``.diagnose(Model, Observations, Diagnoses)`` is ``DiagnosisResult.diagnoses``, a list
of lists of component names (atoms), smallest first; ``[[]]`` means "no fault needed".
"""
from __future__ import annotations

import os
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Iterable, Mapping, Sequence

from diagnosis.engine import DEFAULT_SOLVER, DiagnosisResult, Diagnoser
from diagnosis.loader import load_model


def observation_of(literal_text: str) -> tuple[str, bool]:
    """``"moved"`` -> ("moved", True); ``"~moved"`` -> ("moved", False); spaces inside are dropped."""
    text = "".join(literal_text.split())
    if text.startswith(("~", "!")):
        return text[1:], False
    return text, True


def observations_of(literals: Iterable[str]) -> dict[str, bool]:
    """A list of AgentSpeak observation literals as a mapping; a name given both ways is an error."""
    out: dict[str, bool] = {}
    for lit in literals:
        name, value = observation_of(lit)
        if out.get(name, value) != value:
            raise ValueError(f"observation {name!r} is given both as true and as false")
        out[name] = value
    return out


class DiagnosisService:
    """Thread-safe front of the diagnoser: a model cache and a small pool of worker threads."""

    def __init__(self, workers: int = 2, solver: str = DEFAULT_SOLVER) -> None:
        self._pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="faultmas-diagnosis")
        self._solver = solver
        self._lock = threading.Lock()
        self._cache: dict[str, tuple[tuple[int, int], Diagnoser]] = {}
        self._loading: dict[str, threading.Lock] = {}

    def diagnoser(self, model_path: str | os.PathLike) -> Diagnoser:
        """The cached Diagnoser of a model file, rebuilt when the file's mtime or size changed.

        A replaced Diagnoser is not closed: a query on another thread may still be using it; its
        solver is freed when the last reference goes.
        """
        path = str(Path(model_path).resolve())
        st = os.stat(path)
        stamp = (st.st_mtime_ns, st.st_size)
        with self._lock:
            loading = self._loading.setdefault(path, threading.Lock())
        with loading:  # one load per model at a time; other models load in parallel
            cached = self._cache.get(path)
            if cached and cached[0] == stamp:
                return cached[1]
            diagnoser = Diagnoser(load_model(path), self._solver)
            self._cache[path] = (stamp, diagnoser)
            return diagnoser

    def submit(self, model_path: str | os.PathLike, observations: Mapping[str, bool], *,
               max_card: int | None = None, timeout: float | None = None, max_count: int | None = None,
               min_card_only: bool = False) -> "Future[DiagnosisResult]":
        """All minimal diagnoses (see Diagnoser.diagnose), computed on a worker thread."""
        obs = dict(observations)
        return self._pool.submit(lambda: self.diagnoser(model_path).diagnose(
            obs, max_card=max_card, max_count=max_count, timeout=timeout, min_card_only=min_card_only))

    def submit_possibly_faulty(self, model_path: str | os.PathLike, observations: Mapping[str, bool], *,
                               components: Sequence[str] | None = None,
                               timeout: float | None = None) -> "Future[list[str]]":
        """PosAb (see Diagnoser.possibly_faulty), computed on a worker thread."""
        obs = dict(observations)
        return self._pool.submit(lambda: self.diagnoser(model_path).possibly_faulty(obs, components, timeout))

    def close(self) -> None:
        self._pool.shutdown(wait=True)  # no query runs after this: the solvers can go
        for _, diagnoser in self._cache.values():
            diagnoser.close()
        self._cache.clear()

    def __enter__(self) -> "DiagnosisService":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
