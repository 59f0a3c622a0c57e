"""The camera's optional compiled z-buffer loop (``_zbuffer.pyx``): found, checked against its source, or not.

Why a compiled loop: with 50 robots a camera sees dozens of cylinders, and drawing them costs numpy a
dozen calls each, about a third of a frame (``camera._draw_circles``). ``setup.py`` (``make speedups``)
compiles ``_zbuffer.pyx`` beside the interpreter and records the source's SHA-256 in ``_zbuffer.json``;
a compiled file that does not match the source on disk (edited since) is not used, with one warning,
exactly like the interpreter's guard (``agentspeak/_speedups.py``). Without it (no C compiler,
``FAULTMAS_PURE_PYTHON=1`` at run time, or a stale build) the camera draws with numpy: same pixels,
bit for bit, only slower.

This module must import only the standard library: ``setup.py`` reads it before anything is built.
"""
from __future__ import annotations

import hashlib
import importlib
import json
import logging
import os
from pathlib import Path
from types import ModuleType

SOURCE = Path(__file__).with_name("_zbuffer.pyx")
MANIFEST = Path(__file__).with_name("_zbuffer.json")
MODULE = "robot_bridge.sim._zbuffer"
PURE_ENV = "FAULTMAS_PURE_PYTHON"   # the interpreter's switch (agentspeak/_speedups.py) serves here too

log = logging.getLogger("faultmas.sim")


def source_digest(path: Path | None = None) -> str:
    """SHA-256 of the loop's source (``SOURCE`` by default), as ``setup.py`` records it."""
    return hashlib.sha256((path or SOURCE).read_bytes()).hexdigest()


def load() -> ModuleType | None:
    """The compiled loop if it is built from the source on disk and not switched off; else None."""
    if os.environ.get(PURE_ENV, "") not in ("", "0"):
        return None
    try:
        module = importlib.import_module(MODULE)
    except ImportError:
        return None          # not built: numpy draws
    if SOURCE.exists():      # an installed wheel may ship the compiled file alone: nothing to be stale against
        try:
            built = json.loads(MANIFEST.read_text()).get("digest")
        except (OSError, ValueError, AttributeError):
            built = None
        if built != source_digest():
            log.warning("compiled %s not built from the source on disk; the camera draws with numpy until you "
                        "run make speedups (or: python setup.py build_ext --inplace)", MODULE)
            return None
    return module
