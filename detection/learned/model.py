"""One component's learned model: predicted resource use from features, Mahalanobis distance of the
residuals, threshold for a target false-positive rate. Fitted with scikit-learn; saved as plain arrays.

Training (the paper's three partitions of fault-free runs): a standardised multi-task Elastic Net
(``MultiTaskElasticNetCV``, folds grouped by run so no run is in both a fold's training and test part)
on partition 1; the residuals' covariance (Ledoit-Wolf: targets that never changed in training, such as
the thread count, still get a finite variance) on partition 2; the threshold, the ``1 - target_fpr``
quantile of the squared distances, on partition 3. The covariance gets a floor of half a
counter's resolution on its diagonal (``resolution``): a counter that never moved in partition 2
(page faults, threads) would otherwise have a near-zero variance, and its first healthy one-page or
one-fault step would look like a hundred-sigma deviation (measured on the smoke data: thresholds
of 10^4 and a held-out FPR of 5 %).

Scoring uses the fitted numbers only (scales, coefficients, precision), in numpy: the same arithmetic
before and after saving, bit for bit, a few µs per tick, and a file that does not depend on
scikit-learn's pickles. The file (``.npz``) carries a header: format version, component, and a
fingerprint of its feature and target names; loading a file of another format, or for another
component or system (other channels, other encodings), fails with a ``ModelFileError`` that says which.
"""
from __future__ import annotations

import hashlib
import json
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

FORMAT = "faultmas-perfbugs-model"
FORMAT_VERSION = 1
DEFAULT_TARGET_FPR = 0.005


class ModelFileError(ValueError):
    """A model file that cannot be used: unreadable, corrupt, another format version or another system."""


def fingerprint(component: str, features: Sequence[str], targets: Sequence[str]) -> str:
    """What a model was trained for: the component and the exact names of its inputs and outputs."""
    text = json.dumps([component, list(features), list(targets)])
    return hashlib.sha256(text.encode()).hexdigest()[:16]


@dataclass
class ComponentModel:
    component: str
    features: list[str]
    targets: list[str]
    x_mean: np.ndarray
    x_scale: np.ndarray
    y_mean: np.ndarray
    y_scale: np.ndarray
    coef: np.ndarray               # targets × features, in standardised units
    intercept: np.ndarray
    location: np.ndarray           # the residuals' mean (partition 2)
    precision: np.ndarray          # the inverse of their covariance
    threshold: float               # squared Mahalanobis distance flagged above
    target_fpr: float
    alpha: float = 0.0
    l1_ratio: float = 0.0

    @property
    def fingerprint(self) -> str:
        return fingerprint(self.component, self.features, self.targets)

    def residuals(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        predicted = ((np.atleast_2d(X) - self.x_mean) / self.x_scale) @ self.coef.T + self.intercept
        return (np.atleast_2d(Y) - self.y_mean) / self.y_scale - predicted

    def score(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """Squared Mahalanobis distance of each sample's residuals."""
        r = self.residuals(X, Y) - self.location
        return np.einsum("ij,jk,ik->i", r, self.precision, r)

    def flag(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        return self.score(X, Y) > self.threshold

    # --- files ----------------------------------------------------------------------------------
    def save(self, path: str | Path) -> None:
        header = {"format": FORMAT, "version": FORMAT_VERSION, "component": self.component,
                  "fingerprint": self.fingerprint, "features": self.features, "targets": self.targets,
                  "threshold": self.threshold, "target_fpr": self.target_fpr, "alpha": self.alpha,
                  "l1_ratio": self.l1_ratio}
        with open(path, "wb") as file:        # np.savez would add '.npz' to a name without it
            np.savez_compressed(file, header=np.array(json.dumps(header)), x_mean=self.x_mean,
                                x_scale=self.x_scale, y_mean=self.y_mean, y_scale=self.y_scale, coef=self.coef,
                                intercept=self.intercept, location=self.location, precision=self.precision)

    @classmethod
    def load(cls, path: str | Path, component: str | None = None, features: Sequence[str] | None = None,
             targets: Sequence[str] | None = None) -> "ComponentModel":
        """Read a model file; with ``component``/``features``/``targets`` given, it must be the model of that system."""
        try:
            with np.load(path, allow_pickle=False) as data:
                arrays = {key: data[key] for key in data.files}
            header = json.loads(str(arrays.pop("header")))
        except FileNotFoundError:
            raise ModelFileError(f"{path}: no such model file") from None
        except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError) as exc:
            raise ModelFileError(f"{path}: not a readable model file (corrupt or truncated: {exc})") from None
        if not isinstance(header, dict) or header.get("format") != FORMAT:
            raise ModelFileError(f"{path}: not a faultmas performance-bug model")
        if header.get("version") != FORMAT_VERSION:
            raise ModelFileError(f"{path}: model format version {header.get('version')}, this faultmas reads "
                                 f"version {FORMAT_VERSION}; train it again")
        try:
            model = cls(header["component"], list(header["features"]), list(header["targets"]),
                        threshold=float(header["threshold"]), target_fpr=float(header["target_fpr"]),
                        alpha=float(header["alpha"]), l1_ratio=float(header["l1_ratio"]), **arrays)
        except (KeyError, TypeError) as exc:
            raise ModelFileError(f"{path}: model file is missing {exc}") from None
        if model.fingerprint != header.get("fingerprint") or model.coef.shape != (len(model.targets), len(model.features)):
            raise ModelFileError(f"{path}: model file is inconsistent (fingerprint or shapes do not match)")
        if component is not None and component != model.component:
            raise ModelFileError(f"{path}: model of component {model.component!r}, not {component!r}")
        for what, mine, theirs in (("features", model.features, features), ("targets", model.targets, targets)):
            if theirs is not None and list(theirs) != mine:
                missing = [n for n in mine if n not in theirs][:3]
                extra = [n for n in theirs if n not in mine][:3]
                raise ModelFileError(f"{path}: model of another system: its {what} differ "
                                     f"({len(mine)} in the model, {len(theirs)} here; model only: {missing}, "
                                     f"here only: {extra}); train it on this system's data")
        return model


def fit(component: str, features: list[str], targets: list[str], parts: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray]],
        target_fpr: float = DEFAULT_TARGET_FPR, resolution: Sequence[float] | None = None,
        max_iter: int = 500) -> ComponentModel:
    """Train on three partitions ``(X, Y, run_ids)`` of fault-free samples (see the module's docstring)."""
    from sklearn.covariance import LedoitWolf
    from sklearn.linear_model import MultiTaskElasticNetCV
    from sklearn.model_selection import GroupKFold
    from sklearn.preprocessing import StandardScaler

    (X1, Y1, runs1), (X2, Y2, _), (X3, Y3, _) = parts
    x_scaler, y_scaler = StandardScaler().fit(X1), StandardScaler().fit(Y1)
    groups = len(np.unique(runs1))
    if groups < 2:
        raise ValueError(f"{component}: partition 1 needs at least 2 runs for folds grouped by run, has {groups}")
    folds = list(GroupKFold(n_splits=min(5, groups)).split(X1, Y1, runs1))
    import warnings
    from sklearn.exceptions import ConvergenceWarning
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        # 20 alphas, tol 1e-3, 500 iterations: 4x faster than 30 / 1e-4 / 2000 for the same held-out
        # residuals on the smoke data (measured: mean squared standardised residual equal to 0.003)
        net = MultiTaskElasticNetCV(l1_ratio=[0.1, 0.5, 0.9, 1.0], alphas=20, tol=1e-3, cv=folds,
                                    max_iter=max_iter, n_jobs=1).fit(x_scaler.transform(X1), y_scaler.transform(Y1))
    model = ComponentModel(component, list(features), list(targets), x_scaler.mean_, x_scaler.scale_,
                           y_scaler.mean_, y_scaler.scale_, net.coef_, net.intercept_,
                           location=np.zeros(len(targets)), precision=np.eye(len(targets)), threshold=np.inf,
                           target_fpr=target_fpr, alpha=float(net.alpha_), l1_ratio=float(net.l1_ratio_))
    covariance = LedoitWolf().fit(model.residuals(X2, Y2))
    floor = np.zeros(len(targets)) if resolution is None else (np.asarray(resolution) / 2 / model.y_scale) ** 2
    model.location = covariance.location_
    model.precision = np.linalg.inv(covariance.covariance_ + np.diag(floor))
    model.threshold = threshold(model.score(X3, Y3), target_fpr)
    return model


def threshold(distances: np.ndarray, target_fpr: float) -> float:
    """The ``1 - target_fpr`` quantile of healthy squared distances: the empirical one, or, when larger,
    that of a scaled chi-square matched to their mean and variance (``scipy.stats``).

    Why both: an empirical 99.5 % quantile needs a few hundred samples to mean anything; the smoke
    data's partition 3 has ~60 per component, whose largest value sits near the 98 % point. The
    fitted tail extrapolates (measured on the smoke data: held-out FPR 4.6 % → 2.3 %); with the
    paper's partition 3 (~2,000 samples) the empirical quantile mostly decides."""
    from scipy import stats

    distances = np.asarray(distances, dtype=np.float64)
    empirical = float(np.quantile(distances, 1.0 - target_fpr))
    mean, variance = distances.mean(), distances.var()
    if mean <= 0 or variance <= 0:
        return empirical
    fitted = float(stats.chi2.ppf(1.0 - target_fpr, 2 * mean ** 2 / variance, scale=variance / (2 * mean)))
    return max(empirical, fitted)
