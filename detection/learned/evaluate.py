"""Train the learned model and the baselines on a data set's fault-free runs, score the held-out runs,
and make the paper's Table I (plus AUC per fault kind and per component, and ROC curves).

Partitions of the fault-free runs, in run order: the last ``held_out`` are test runs (with every faulty
run); of the rest, half fit the Elastic Net (partition 1), a quarter the covariance (2), a quarter the
threshold (3), rounding in favour of partition 3; at least 2 + 1 + 1 runs (folds grouped by run).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from detection.learned.baselines import OneClassSvmDetector, RandomDetector
from detection.learned.counters import RESOLUTION, TARGET_NAMES
from detection.learned.dataset import Dataset
from detection.learned.metrics import Scores, auc_by, table_row
from detection.learned.model import DEFAULT_TARGET_FPR, ComponentModel, fit

DETECTORS = ("model", "ocsvm", "random")


def partitions(fault_free: list[int], held_out: int) -> tuple[list[int], list[int], list[int], list[int]]:
    """(partition 1, 2, 3, held-out test) run ids; raises ``ValueError`` when there are too few runs."""
    runs = sorted(fault_free)
    if len(runs) < 4 + held_out:
        raise ValueError(f"{len(runs)} fault-free runs: training needs at least 4 (2 + 1 + 1) plus "
                         f"{held_out} held out")
    test, train = runs[len(runs) - held_out:], runs[:len(runs) - held_out]
    n1 = len(train) // 2
    n2 = (len(train) - n1) // 2
    return train[:n1], train[n1:n1 + n2], train[n1 + n2:], test


@dataclass
class Evaluation:
    models: dict[str, ComponentModel]
    scores: dict[str, Scores]
    faults: list[dict]
    partitions: tuple[list[int], ...]
    training_s: float
    target_fpr: float
    rows: dict[str, dict[str, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.rows = {name: table_row(s, self.faults) for name, s in self.scores.items()}

    def auc_by_kind(self) -> dict[str, dict[str, float]]:
        return {name: auc_by(s, "kind") for name, s in self.scores.items()}

    def auc_by_component(self) -> dict[str, dict[str, float]]:
        return {name: auc_by(s, "component") for name, s in self.scores.items()}

    def detections(self) -> list[dict]:
        """Every fault instance, whether each detector flagged it within the window, and the share of
        its seconds each flagged (``<detector>_share``: a single lucky flag also counts as detected)."""
        from detection.learned.metrics import detected, flagged_share
        return [dict(f, **{name: detected(s, f) for name, s in self.scores.items()},
                     **{f"{name}_share": flagged_share(s, f) for name, s in self.scores.items()}) for f in self.faults]


def train_models(dataset: Dataset, parts, target_fpr: float, progress: Callable[[str], None] = lambda _: None) -> dict[str, ComponentModel]:
    p1, p2, p3 = parts[:3]
    models = {}
    for n, (name, samples) in enumerate(sorted(dataset.components.items()), 1):
        progress(f"training {name} ({n}/{len(dataset.components)})")
        split = [samples.select(p) for p in (p1, p2, p3)]
        models[name] = fit(name, samples.features, list(TARGET_NAMES),
                           [(s.X, s.Y, s.run) for s in split], target_fpr, RESOLUTION)
    return models


def evaluate(dataset: Dataset, target_fpr: float = DEFAULT_TARGET_FPR, held_out: int | None = None,
             progress: Callable[[str], None] = lambda _: None, seed: int = 0) -> Evaluation:
    fault_free = dataset.fault_free_runs()
    if held_out is None:
        held_out = 1 if len(fault_free) < 10 else 2
    parts = partitions(fault_free, held_out)
    test_runs = parts[3] + dataset.faulty_runs()
    started = time.process_time()
    models = train_models(dataset, parts, target_fpr, progress)
    training_s = time.process_time() - started
    columns: dict[str, list] = {name: [] for name in DETECTORS}
    for name, samples in sorted(dataset.components.items()):
        progress(f"scoring {name}")
        train = samples.select(parts[0] + parts[1])
        ocsvm = OneClassSvmDetector.fit(train.X, train.Y, target_fpr)
        test = samples.select(test_runs)
        model = models[name]
        model_score = model.score(test.X, test.Y)
        per = {"model": (model_score / model.threshold, model_score > model.threshold),
               "ocsvm": (ocsvm.score(test.X, test.Y), ocsvm.flag(test.X, test.Y)),
               "random": (RandomDetector(seed + len(columns["random"])).score(test.X, test.Y), None)}
        per["random"] = (per["random"][0], per["random"][0] < RandomDetector.rate)
        for detector, (score, flag) in per.items():
            columns[detector].append((np.full(len(test.run), name, dtype=object), test.run, test.tick,
                                      test.label, test.kind, score, flag))
    scores = {d: Scores(*(np.concatenate(parts_) for parts_ in zip(*columns[d]))) for d in DETECTORS}
    faults = [f for f in dataset.faults() if f["run"] in test_runs]
    return Evaluation(models, scores, faults, parts, training_s, target_fpr)


def plot_roc(evaluation: Evaluation, path: str | Path, title: str = "") -> None:
    """ROC curves of the three detectors (micro-averaged over all samples) into ``path``."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from sklearn.metrics import roc_curve

    figure, axes = plt.subplots(figsize=(5.5, 5))
    for name, scores in evaluation.scores.items():
        if scores.label.any() and not scores.label.all():
            fpr, tpr, _ = roc_curve(scores.label, scores.score)
            axes.plot(fpr, tpr, label=f"{name} (AUC {evaluation.rows[name]['auc']:.3f})")
    chance = np.logspace(-3, 0, 50)
    axes.plot(chance, chance, color="grey", linestyle=":", linewidth=1)
    axes.set_xscale("log")                      # the operating range is FPR < 2 %: spread it out
    axes.set_xlim(1e-3, 1.0)
    axes.axvline(evaluation.target_fpr, color="grey", linestyle="--", linewidth=1, label=f"target FPR {evaluation.target_fpr:g}")
    axes.set_xlabel("false-positive rate (log scale)")
    axes.set_ylabel("true-positive rate")
    axes.set_title(title or "Performance bugs: ROC, all (component, run, second) samples")
    axes.legend(loc="lower right")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
