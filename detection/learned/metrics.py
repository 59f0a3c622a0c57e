"""The paper's Table I measures, over all (component, run, second) samples, with scikit-learn's metrics.

F0.1 (precision weighted ten times recall), false-positive rate, detection rate (a fault instance is
detected when its component is flagged within ``DETECTION_WINDOW_S`` of its start) and the
micro-averaged ROC AUC (all samples pooled; each detector's scores are made comparable across
components first, the learned model's by dividing by each component's threshold).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DETECTION_WINDOW_S = 80.0


@dataclass
class Scores:
    """Per sample: component, run, tick (epoch s), truth, the detector's score and flag."""

    component: np.ndarray
    run: np.ndarray
    tick: np.ndarray
    label: np.ndarray
    kind: np.ndarray
    score: np.ndarray
    flag: np.ndarray


def f_beta(scores: Scores, beta: float = 0.1) -> float:
    from sklearn.metrics import fbeta_score
    return float(fbeta_score(scores.label, scores.flag, beta=beta, zero_division=0.0))


def false_positive_rate(scores: Scores) -> float:
    negatives = ~scores.label
    return float(scores.flag[negatives].mean()) if negatives.any() else float("nan")


def roc_auc(scores: Scores, mask: np.ndarray | None = None) -> float:
    from sklearn.metrics import roc_auc_score
    label = scores.label if mask is None else scores.label[mask]
    score = scores.score if mask is None else scores.score[mask]
    if label.all() or not label.any():
        return float("nan")
    return float(roc_auc_score(label, score))


def detected(scores: Scores, fault: dict) -> bool:
    """Was ``fault`` (component, run, start) flagged in its component within the detection window?"""
    mask = (scores.component == fault["component"]) & (scores.run == fault["run"]) & \
        (scores.tick >= fault["start"]) & (scores.tick < fault["start"] + DETECTION_WINDOW_S)
    return bool(scores.flag[mask].any())


def flagged_share(scores: Scores, fault: dict) -> float:
    """The share of ``fault``'s seconds flagged in its component."""
    mask = (scores.component == fault["component"]) & (scores.run == fault["run"]) & \
        (scores.tick >= fault["start"]) & (scores.tick < fault["end"])
    return float(scores.flag[mask].mean()) if mask.any() else float("nan")


def detection_rate(scores: Scores, faults: list[dict]) -> float:
    return float(np.mean([detected(scores, f) for f in faults])) if faults else float("nan")


def auc_by(scores: Scores, key: str) -> dict[str, float]:
    """AUC per fault kind (its faulty samples against every healthy sample) or per component."""
    if key == "kind":
        return {k: roc_auc(scores, (scores.kind == k) | ~scores.label)
                for k in sorted(set(scores.kind[scores.label]))}
    return {c: roc_auc(scores, scores.component == c) for c in sorted(set(scores.component))}


def table_row(scores: Scores, faults: list[dict]) -> dict[str, float]:
    return {"f0.1": f_beta(scores), "fpr": false_positive_rate(scores),
            "detection_rate": detection_rate(scores, faults), "auc": roc_auc(scores)}
