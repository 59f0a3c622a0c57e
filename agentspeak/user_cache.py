"""Where faultmas keeps what it builds once and reuses between runs (grammar tables, parsed programs, compiled
netlists), and how an entry is written and read back.

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


def write_entry(path: Path, data: bytes, max_entries: int) -> None:
    """Keep ``data`` (an entry, serialized by the caller) at ``path``, atomically (a reader sees the old entry or
    the new one, never half of one), then only the ``max_entries`` most recently written entries of that
    directory with the same suffix. Nothing is raised: a read-only or full disk only costs the rebuild."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        partial = path.with_name(f".{path.name}.{os.getpid()}")
        partial.write_bytes(data)
        os.replace(partial, path)
        _prune(path.parent, path.suffix, max_entries)
    except OSError:
        pass


def _prune(directory: Path, suffix: str, max_entries: int) -> None:
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
