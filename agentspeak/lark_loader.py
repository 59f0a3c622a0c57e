"""Lark LALR parsers built once per grammar text, and a clear refusal when the wrong ``lark`` is installed.

Building the LALR tables of ``agentspeak.lark`` costs most of a short run (~0.5 s), so every grammar is
loaded through ``lalr_parser``: Lark's own cache (its tables pickled with a digest of the grammar, the
options, Lark's and Python's versions, which Lark checks on load), stored in the user's cache directory
under a file name that holds the grammar's digest. An edited grammar (another branch, an upgrade) gets a
new file, never a stale table; a directory that cannot be written only costs the build on every start.

The ROS 2 wheels depend on ``lark-parser`` 0.12, which installs the same ``lark`` package as Lark 1.x
and, installed last, silently replaces it; our grammars then fail deep in the parser. ``require_lark_1``
refuses that at import time with the one-line fix (``WrongLarkError``), which ``faultmas`` prints as is.
"""
from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from agentspeak.user_cache import CACHE_ENV, cache_dir  # noqa: F401  (CACHE_ENV: named here by tests and docs)

if TYPE_CHECKING:
    from lark import Lark

LARK_REQUIREMENT = "lark>=1.2,<2"


class WrongLarkError(ImportError):
    """The installed ``lark`` package is not Lark 1.x (usually ``lark-parser`` 0.12 from the ROS wheels)."""


def fix_command() -> str:
    """The one command that puts Lark 1.x back into this interpreter's environment."""
    return f"{sys.executable} -m pip install --force-reinstall --no-deps '{LARK_REQUIREMENT}'"


def installed_lark_version() -> str | None:
    """The version of the ``lark`` package ``import lark`` would give, read without importing it (Lark's
    import costs more than the check is worth for commands that never parse); None if there is none."""
    module = sys.modules.get("lark")
    if module is not None:
        return str(getattr(module, "__version__", "unknown"))
    import importlib.util

    spec = importlib.util.find_spec("lark")
    if spec is None or not spec.origin:
        return None
    try:
        found = re.search(r"^__version__\s*(?::\s*str\s*)?=\s*[\"']([^\"']+)", Path(spec.origin).read_text(), re.M)
    except OSError:
        return "unknown"
    return found.group(1) if found else "unknown"


def require_lark_1() -> None:
    """Raise ``WrongLarkError`` (with the fix) unless ``import lark`` gives Lark 1.x."""
    version = installed_lark_version()
    if version is None:
        raise WrongLarkError(f"faultmas needs Lark 1.x, which is not installed; fix: {fix_command()}")
    if not version.startswith("1."):
        raise WrongLarkError(
            f"faultmas needs Lark 1.x, but the installed 'lark' package is version {version} (the ROS 2 wheels' "
            f"lark-parser replaced it); fix: {fix_command()}")


require_lark_1()      # at import: the modules that parse import this one before ``lark``


def lalr_parser(grammar_file: Path, **options: Any) -> Lark:
    """``Lark(grammar, parser="lalr", **options)`` with its tables built once and then loaded from the cache.

    The file name holds a digest of the grammar text and the options, so a changed grammar never meets
    an old table (Lark checks its own digest on load too, and rebuilds on a mismatch or a damaged file)."""
    import hashlib                     # here: every command imports this module, few build a parser

    from lark import Lark

    text = Path(grammar_file).read_text(encoding="utf-8")
    key = repr(sorted((k, v) for k, v in options.items() if k not in ("transformer", "_plugins")))
    digest = hashlib.sha256(f"{text}\0{key}\0{'_plugins' in options}".encode()).hexdigest()[:20]
    directory = cache_dir()
    target = directory / f"{Path(grammar_file).stem}-{digest}-py{sys.version_info[0]}{sys.version_info[1]}.lark"
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError:        # read-only home: correct, only slower
        return Lark(text, parser="lalr", **options)
    # Lark writes the file in place (its digest covers the path, so no write-and-rename): processes starting
    # together may all build it, and one that reads a half-written file rebuilds (Lark catches that).
    return Lark(text, parser="lalr", cache=str(target), **options)
