"""The paper's baselines, trained and scored on the same samples as the learned model.

One-Class SVM (scikit-learn) on the standardised features and targets together (it has no notion of
a prediction, so it sees both), ``nu`` = the target false-positive rate, RBF kernel with
``gamma='scale'``; trained on partition 1 and 2 of the fault-free runs. Score: minus its decision
function. Random: a fair coin per sample, score uniform in [0, 1) (seeded, reproducible).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class OneClassSvmDetector:
    scaler: object
    svm: object

    @classmethod
    def fit(cls, X: np.ndarray, Y: np.ndarray, target_fpr: float) -> "OneClassSvmDetector":
        from sklearn.preprocessing import StandardScaler
        from sklearn.svm import OneClassSVM

        Z = np.hstack([X, Y])
        scaler = StandardScaler().fit(Z)
        return cls(scaler, OneClassSVM(nu=max(target_fpr, 1e-3), gamma="scale").fit(scaler.transform(Z)))

    def score(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        return -self.svm.decision_function(self.scaler.transform(np.hstack([X, Y])))

    def flag(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        return self.score(X, Y) > 0.0


@dataclass
class RandomDetector:
    seed: int = 0
    rate: float = 0.5

    def score(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        return np.random.default_rng(self.seed + len(X)).random(len(X))

    def flag(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        return self.score(X, Y) < self.rate
