"""Where faultmas keeps what it builds once and reuses between runs (grammar tables, parsed programs).

Nothing in it is needed: a missing, damaged or read-only directory only makes start-up slower.
"""
from __future__ import annotations

import os
from pathlib import Path

CACHE_ENV = "FAULTMAS_CACHE_DIR"
"""Where the cache goes (default: ``$XDG_CACHE_HOME/faultmas`` or ``~/.cache/faultmas``)."""


def cache_dir() -> Path:
    """The cache directory (not created here)."""
    configured = os.environ.get(CACHE_ENV)
    if configured:
        return Path(configured)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "faultmas"
