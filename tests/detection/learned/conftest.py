"""The smoke data set (recorded from the real ROS 2 team, in the repository) and models trained on it once."""
from __future__ import annotations

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
def smoke_evaluation(smoke):
    from detection.learned.evaluate import evaluate
    return evaluate(smoke)
