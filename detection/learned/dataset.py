"""A recorded data set as the detector's samples: per component, per run, per tick, its features (from
the channels it reads and writes), its targets (process counters) and whether a fault was active in it.
"""
from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from detection.learned.counters import TARGET_NAMES, targets_from_counters
from detection.learned.features import feature_names, window_features
from detection.learned.record import event_times


class DatasetError(ValueError):
    """A data set directory that cannot be read; names the file and what was expected."""


@dataclass
class ComponentSamples:
    """All ticks of one component over the runs of a data set (rows line up across the arrays)."""

    component: str
    features: list[str]
    X: np.ndarray
    Y: np.ndarray
    run: np.ndarray
    tick: np.ndarray
    label: np.ndarray
    kind: np.ndarray

    def select(self, runs) -> "ComponentSamples":
        mask = np.isin(self.run, list(runs))
        return ComponentSamples(self.component, self.features, self.X[mask], self.Y[mask], self.run[mask],
                                self.tick[mask], self.label[mask], self.kind[mask])


@dataclass
class Dataset:
    path: Path
    manifest: dict
    components: dict[str, ComponentSamples] = field(default_factory=dict)

    @property
    def runs(self) -> list[dict]:
        return self.manifest["runs"]

    def fault_free_runs(self) -> list[int]:
        return [r["id"] for r in self.runs if not r["faults"]]

    def faulty_runs(self) -> list[int]:
        return [r["id"] for r in self.runs if r["faults"]]

    def faults(self) -> list[dict]:
        """Every ground-truth fault instance with its run id."""
        return [dict(f, run=r["id"]) for r in self.runs for f in r["faults"]]


def component_channels(manifest: dict, component: str) -> list[tuple[str, list[str]]]:
    """The channels of ``component`` (union over runs, sorted) with their event columns: a ROS 2
    channel's are the same in every run; a JSON channel's (Zenoh) are the union over the runs, in
    the order first seen (a path that appears only in some runs is 0 in the others)."""
    channels: dict[str, list[str]] = {}
    for run in manifest["runs"]:
        spec = run["components"].get(component)
        if spec is None:
            continue
        for topic in set(spec["inputs"]) | set(spec["outputs"]):
            columns = channels.setdefault(topic, list(run["channels"][topic]["columns"]))
            columns += [c for c in run["channels"][topic]["columns"] if c not in columns]
    return sorted(channels.items())


def features_for_run(arrays, channels: list[tuple[str, list[str]]], ticks: np.ndarray,
                     run_columns: dict[str, list[str]] | None = None) -> np.ndarray:
    """``channels``' features at ``ticks``; ``run_columns`` (channel → the columns this run recorded)
    aligns a run whose JSON channel saw other paths than the union in ``channels``."""
    parts = []
    for topic, columns in channels:
        times = event_times(arrays, topic)
        if times is not None:
            values = arrays[f"events/{topic}/x"].astype(np.float64)
            recorded = (run_columns or {}).get(topic, columns)
            if recorded != columns:
                aligned = np.zeros((len(values), len(columns)))
                where = {c: i for i, c in enumerate(recorded)}
                for j, c in enumerate(columns):
                    if c in where:
                        aligned[:, j] = values[:, where[c]]
                values = aligned
        else:                                         # silent in this run
            times, values = np.empty(0), np.empty((0, len(columns)))
        parts.append(window_features(times, values, ticks))
    return np.hstack(parts) if parts else np.empty((len(ticks), 0))


def load(path: str | Path, progress=None) -> Dataset:
    """Read ``manifest.json`` and every run file of a data set directory."""
    path = Path(path)
    manifest_path = path / "manifest.json"
    try:
        manifest = json.loads(manifest_path.read_text())
    except OSError as exc:
        raise DatasetError(f"{manifest_path}: no data set here ({exc.strerror}); generate one with "
                           "'faultmas experiment perfbugs --generate'") from None
    except json.JSONDecodeError as exc:
        raise DatasetError(f"{manifest_path}:{exc.lineno}:{exc.colno}: not JSON ({exc.msg})") from None
    if manifest.get("format") != 1 or not isinstance(manifest.get("runs"), list):
        raise DatasetError(f"{manifest_path}: not a perfbugs data set manifest (format 1 with 'runs')")
    dataset = Dataset(path, manifest)
    names = sorted({c for r in manifest["runs"] for c in r["components"]})
    channels = {c: component_channels(manifest, c) for c in names}
    rows: dict[str, list] = {c: [] for c in names}
    for n, run in enumerate(manifest["runs"], 1):
        if progress:
            progress(f"reading run {n}/{len(manifest['runs'])}")
        file = path / run["file"]
        try:
            with np.load(file) as arrays:
                arrays = dict(arrays)
        except (OSError, ValueError, zipfile.BadZipFile) as exc:
            raise DatasetError(f"{file}: cannot read run {run['id']} ({exc})") from None
        ticks = arrays["ticks"]
        for c in names:
            if f"counters/{c}" not in arrays:
                continue
            Y = targets_from_counters(arrays[f"counters/{c}"])
            X = features_for_run(arrays, channels[c], ticks[1:],
                                 {t: spec["columns"] for t, spec in run["channels"].items()})
            label = np.zeros(len(Y), dtype=bool)
            kind = np.full(len(Y), "", dtype=object)
            for fault in run["faults"]:
                if fault["component"] == c:
                    active = (ticks[1:] >= fault["start"]) & (ticks[1:] < fault["end"])
                    label |= active
                    kind[active] = fault["kind"]
            ok = np.isfinite(Y).all(axis=1)
            rows[c].append((X[ok], Y[ok], np.full(ok.sum(), run["id"]), ticks[1:][ok], label[ok], kind[ok]))
    for c in names:
        if not rows[c]:
            continue
        X, Y, run_ids, ticks, label, kind = (np.concatenate(parts) for parts in zip(*rows[c]))
        names_c = [n for topic, columns in channels[c] for n in feature_names(topic, columns)]
        dataset.components[c] = ComponentSamples(c, names_c, X, Y, run_ids, ticks, label, kind)
    return dataset


__all__ = ["Dataset", "ComponentSamples", "DatasetError", "load", "TARGET_NAMES"]
