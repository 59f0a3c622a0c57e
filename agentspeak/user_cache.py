"""Where faultmas keeps what it builds once and reuses between runs (grammar tables, parsed programs, compiled
netlists), and how an entry is written.

Nothing in it is needed: a missing, damaged or read-only directory only makes start-up slower. Paths here are
strings (``os.path``): ``pathlib`` is imported only by ``cache_dir``, as its import is a tenth of a short
``faultmas diagnose`` (issue 23), which uses ``cache_path``.
"""
from __future__ import annotations

import os

TYPE_CHECKING = False     # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:
    from pathlib import Path

CACHE_ENV = "FAULTMAS_CACHE_DIR"
"""Where the cache goes (default: ``$XDG_CACHE_HOME/faultmas`` or ``~/.cache/faultmas``)."""


def cache_path() -> str:
    """The cache directory (not created here)."""
    configured = os.environ.get(CACHE_ENV)
    if configured:
        return configured
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "faultmas")


def cache_dir() -> Path:
    """The cache directory as a ``Path`` (not created here)."""
    from pathlib import Path

    return Path(cache_path())


def write_entry(path: str | os.PathLike, data: bytes, max_entries: int) -> None:
    """Keep ``data`` (an entry, serialized by the caller) at ``path``, atomically (a reader sees the old entry or
    the new one, never half of one), then only the ``max_entries`` most recently written entries of that
    directory with the same suffix. Nothing is raised: a read-only or full disk only costs the rebuild."""
    path = os.fspath(path)
    directory, name = os.path.split(path)
    try:
        os.makedirs(directory, exist_ok=True)
        partial = os.path.join(directory, f".{name}.{os.getpid()}")
        with open(partial, "wb") as f:
            f.write(data)
        os.replace(partial, path)
        _prune(directory, os.path.splitext(name)[1], max_entries)
    except OSError:
        pass


def _prune(directory: str, suffix: str, max_entries: int) -> None:
    entries = [e for e in os.scandir(directory) if e.name.endswith(suffix) and not e.name.startswith(".")]
    if len(entries) <= max_entries:
        return
    entries.sort(key=lambda e: e.stat().st_mtime_ns)
    for entry in entries[:len(entries) - max_entries]:
        try:
            os.remove(entry.path)
        except OSError:
            pass


def code_files(root: str, folders: tuple[str, ...] = ("",), suffixes: tuple[str, ...] = (".py",)) -> tuple:
    """(name, size, modification time) of the files with these suffixes in ``root``'s ``folders``: what identifies
    the code that made an entry (an edit, another branch, an upgrade or a rebuild changes it)."""
    files = []
    for folder in folders:
        with os.scandir(os.path.join(root, folder)) as entries:
            for entry in entries:
                if entry.name.endswith(suffixes):
                    stat = entry.stat()
                    files.append((os.path.join(folder, entry.name), stat.st_size, stat.st_mtime_ns))
    return tuple(sorted(files))
