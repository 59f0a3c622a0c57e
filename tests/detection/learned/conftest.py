"""The smoke data set (recorded from the real ROS 2 team, in the repository) and models trained on it once."""
from __future__ import annotations

import fcntl
import os
import pickle

import pytest

from experiments.perfbugs import data_dir

SMOKE = data_dir("smoke")


@pytest.fixture(scope="session")
def smoke():
    from detection.learned.dataset import load
    if not (SMOKE / "manifest.json").exists():
        pytest.fail(f"{SMOKE} is missing: 'faultmas experiment perfbugs --profile smoke --generate' makes it")
    return load(SMOKE)


@pytest.fixture(scope="session")
def smoke_evaluation(smoke, tmp_path_factory):
    """Trained once per run (~8 s of CPU). Under pytest-xdist the workers share it: the first one to need it
    trains and leaves a pickle in the run's common temporary folder, the others wait for it and read it."""
    from detection.learned.evaluate import evaluate
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        return evaluate(smoke)
    shared = tmp_path_factory.getbasetemp().parent / "smoke-evaluation.pickle"
    with open(shared.with_suffix(".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if shared.exists():
            return pickle.loads(shared.read_bytes())
        evaluation = evaluate(smoke)
        shared.write_bytes(pickle.dumps(evaluation))
        return evaluation
