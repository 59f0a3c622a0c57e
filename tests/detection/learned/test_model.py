"""The component model: trained on three partitions, saved, reloaded bit for bit, refused clearly when
the file is corrupt, of another format version or of another system."""
from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest

from detection.learned.model import FORMAT_VERSION, ComponentModel, ModelFileError, fit

FEATURES = [f"/t|mean2.5s|x{i}" for i in range(6)]
TARGETS = ["cpu", "rss", "threads"]
W = np.random.default_rng(42).normal(size=(6, 3))
W[3:] = 0.0                                              # three features do not matter


def _runs(rng, runs, ticks=80, shift=0.0):
    parts = []
    for run in runs:
        X = rng.normal(size=(ticks, 6)) * [1, 2, 3, 1, 1, 1] + 10
        Y = X @ W + rng.normal(scale=0.1, size=(ticks, 3)) + [0.0, 50.0, 18.0]
        Y[:, 2] = 18.0                                   # a target that never changes in training
        Y[:, 1] += shift
        parts.append((X, Y, np.full(ticks, run)))
    return [tuple(np.concatenate(p) for p in zip(*parts))]


@pytest.fixture(scope="module")
def trained():
    rng = np.random.default_rng(7)
    parts = _runs(rng, [0, 1, 2]) + _runs(rng, [3]) + _runs(rng, [4])
    return fit("faulty_motion_decomposer", FEATURES, TARGETS, parts, target_fpr=0.01), rng


def test_fault_free_samples_stay_under_the_threshold_and_a_shift_is_flagged(trained):
    model, rng = trained
    (X, Y, _), = _runs(np.random.default_rng(7), [9])         # the same system, a new run
    assert model.flag(X, Y).mean() <= 0.05
    leaking = Y.copy()
    leaking[:, 1] += np.linspace(0, 20, len(Y))             # RSS grows
    assert model.flag(X, leaking)[len(Y) // 2:].all()
    threads = Y.copy()
    threads[40:, 2] += 3                                    # never varied in training, still flagged
    assert model.flag(X, threads)[40:].all()


def test_a_saved_model_reloads_and_scores_identically(trained, tmp_path):
    model, _ = trained
    (X, Y, _), = _runs(np.random.default_rng(1), [5])
    path = tmp_path / "faulty_motion_decomposer"             # no suffix: saved under exactly this name
    model.save(path)
    loaded = ComponentModel.load(path, component="faulty_motion_decomposer", features=FEATURES, targets=TARGETS)
    assert np.array_equal(loaded.score(X, Y), model.score(X, Y))
    assert loaded.threshold == model.threshold and loaded.fingerprint == model.fingerprint


def test_a_corrupt_or_truncated_model_file_gives_a_clear_error(trained, tmp_path):
    model, _ = trained
    path = tmp_path / "m.npz"
    model.save(path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(ModelFileError, match=r"m\.npz: not a readable model file \(corrupt or truncated"):
        ComponentModel.load(path)
    path.write_bytes(b"hello")
    with pytest.raises(ModelFileError, match="corrupt or truncated"):
        ComponentModel.load(path)
    with pytest.raises(ModelFileError, match="no such model file"):
        ComponentModel.load(tmp_path / "missing.npz")


def _rewrite_header(path, change):
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    header = json.loads(str(arrays["header"]))
    change(header)
    arrays["header"] = np.array(json.dumps(header))
    with open(path, "wb") as file:
        np.savez(file, **arrays)


def test_a_model_of_another_version_or_system_is_refused(trained, tmp_path):
    model, _ = trained
    path = tmp_path / "m.npz"
    model.save(path)
    with pytest.raises(ModelFileError, match="model of component 'faulty_motion_decomposer', not 'helper_kobuki_sim'"):
        ComponentModel.load(path, component="helper_kobuki_sim")
    with pytest.raises(ModelFileError, match="model of another system: its features differ"):
        ComponentModel.load(path, features=FEATURES[:-1] + ["/t|mean2.5s|other"])
    _rewrite_header(path, lambda h: h.update(version=FORMAT_VERSION + 1))
    with pytest.raises(ModelFileError, match=f"format version {FORMAT_VERSION + 1}, this faultmas reads version {FORMAT_VERSION}"):
        ComponentModel.load(path)
    model.save(path)
    _rewrite_header(path, lambda h: h["features"].reverse())      # edited by hand: fingerprint no longer fits
    with pytest.raises(ModelFileError, match="inconsistent"):
        ComponentModel.load(path)
    with zipfile.ZipFile(tmp_path / "other.npz", "w") as z:
        z.writestr("header.npy", b"")
    with pytest.raises(ModelFileError):
        ComponentModel.load(tmp_path / "other.npz")


def test_partition_one_needs_two_runs_for_grouped_folds():
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="partition 1 needs at least 2 runs"):
        fit("c", FEATURES, TARGETS, _runs(rng, [0]) + _runs(rng, [1]) + _runs(rng, [2]))
