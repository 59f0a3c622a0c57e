"""Shared fixtures for the diagnosis tests: model files, the c17 copy and the ISCAS-85 folder."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import pytest

REPO = Path(__file__).resolve().parents[2]
ISCAS = REPO.parent / "shared" / "benchmarks" / "iscas85"


@pytest.fixture(scope="session")
def data_dir() -> Path:
    return Path(__file__).resolve().parent / "data"


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


@pytest.fixture(scope="session")
def iscas() -> Path:
    if not (ISCAS / "c432.bench").is_file():
        pytest.skip(f"ISCAS-85 circuits not found at {ISCAS} (../shared/benchmarks/iscas85)")
    return ISCAS


@pytest.fixture
def write(tmp_path: Path) -> Callable[[str, str], Path]:
    """write(name, text) -> path of a new file in the test's temporary folder."""
    def _write(name: str, text: str) -> Path:
        path = tmp_path / name
        path.write_text(text, encoding="utf-8")
        return path
    return _write
