"""The optional compiled interpreter: which modules ``setup.py`` compiles with Cython, and the guard that
makes sure a compiled module is only used while it matches its source.

Why: the reasoning cycle is pure Python, and CPython spends much of a cycle dispatching bytecode and
looking attributes up. The same ``.py`` files are compiled by Cython into extension modules; a few
``.pxd`` files beside them (``agent``, ``intentions``, ``program``, ``communication``) declare the
objects of the reasoning cycle (Agent, Intention, IntendedMeans, Frame, Event, Trigger, Message) as C
types, so the compiled cycle reads their fields as struct members. Measured against the sources run by
CPython 3.11: the ring about 85% faster, count about 20%. Nothing is written twice: the sources stay plain
Python (the ``.pxd`` files only declare types), and every module also runs from source (no compiler,
``FAULTMAS_PURE_PYTHON=1`` at build or run time, or a stale build).

A compiled file sits next to its source and Python prefers it, so an edited ``solver.py`` would be
silently ignored until the next build. The build therefore records each source's SHA-256 (its ``.pxd``
included) in ``_speedups.json``; at import, if any module's source has changed since, the whole
interpreter is loaded from the ``.py`` files instead (the compiled modules share C types, so they cannot
be mixed with modules from source), with one warning that names the changed modules and says how to
rebuild. ``FAULTMAS_PURE_PYTHON=1`` at run time loads every module from source (for cProfile, a
debugger, or to compare the two).

This module must import only the standard library: ``setup.py`` reads it before anything is built.
"""
from __future__ import annotations

import importlib.machinery
import os
import sys

# Imported where used, not here: this module runs at every start of faultmas (issue 23: start-up time), and
# hashlib, logging, shlex, shutil, sysconfig and importlib.util are needed only by the build or on a stale
# build (json to read the record). Paths are strings (``os.path``), taken as ``str`` or ``os.PathLike``:
# importing ``pathlib`` (with ``urllib.parse``, ``fnmatch``...) was a tenth of a short ``faultmas diagnose``.

TYPE_CHECKING = False     # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:
    from typing import Union
    StrPath = Union[str, "os.PathLike[str]"]

# The interpreter's modules, compiled when a C compiler and Cython are at hand. Left out: the parser (a
# Lark transformer, already served by lark-cython), the command line and the project-file reader (cold
# code), ``errors`` (exception classes: compiled they are ordinary Python classes all the same, and a compiled
# module there would make ``faultmas diagnose``, which needs only it, source_text and user_cache, pay the
# stale-source check: see ``_Guard``), and this module (it decides what is imported from where). agent.py is
# compiled only together with agent.pxd: compiled as a plain class, the reasoning cycle ran count 13% slower
# than from source (CPython 3.11's specialised attribute access beats the generic lookups compiled code makes on
# plain objects).
COMPILED_MODULES = (
    "agentspeak.agent", "agentspeak.arch", "agentspeak.beliefs", "agentspeak.body", "agentspeak.communication",
    "agentspeak.copier", "agentspeak.fork", "agentspeak.ground_terms",
    "agentspeak.intentions", "agentspeak.program", "agentspeak.runtime", "agentspeak.solver",
    "agentspeak.terms", "agentspeak.unify",
    "agentspeak.stdlib.bdi", "agentspeak.stdlib.beliefs", "agentspeak.stdlib.communication",
    "agentspeak.stdlib.functions", "agentspeak.stdlib.lists", "agentspeak.stdlib.output",
    "agentspeak.stdlib.plans", "agentspeak.stdlib.registry", "agentspeak.stdlib.strings",
    "agentspeak.stdlib.system",
)
MANIFEST = "_speedups.json"
PURE_ENV = "FAULTMAS_PURE_PYTHON"
REBUILD = "make speedups (or: python setup.py build_ext --inplace)"

_PACKAGE_DIR = os.path.dirname(os.path.realpath(__file__))


def source_path(module: str, package_dir: StrPath = _PACKAGE_DIR) -> str:
    """``agentspeak.stdlib.lists`` -> ``<package_dir>/stdlib/lists.py``."""
    return os.path.join(package_dir, *module.split(".")[1:]) + ".py"


def _declarations(path: StrPath) -> str:
    """The ``.pxd`` beside a module's ``.py`` (it may not exist)."""
    return os.fspath(path).removesuffix(".py") + ".pxd"


def source_digest(path: StrPath) -> str:
    """SHA-256 of a module's ``.py`` and, if there is one, of the ``.pxd`` beside it (its C types)."""
    import hashlib

    with open(path, "rb") as f:
        digest = hashlib.sha256(f.read())
    if os.path.exists(_declarations(path)):
        with open(_declarations(path), "rb") as f:
            digest.update(b"\0pxd\0" + f.read())
    return digest.hexdigest()


def source_stamp(path: StrPath) -> str:
    """Size and modification time of a module's ``.py`` and ``.pxd``: what the build saw, cheaply compared at
    every start (as Python's own ``.pyc`` check); only a file whose stamp differs is hashed."""
    stamps = []
    for file in (path, _declarations(path)):
        try:
            info = os.stat(file)
        except OSError:
            continue
        stamps.append(f"{info.st_size}:{info.st_mtime_ns}")
    return "/".join(stamps)


STAMPS = "stamps"
"""The manifest's key for ``{module: source_stamp}`` (beside ``{module: source_digest}``)."""


def pure_requested() -> bool:
    return os.environ.get(PURE_ENV, "") not in ("", "0")


def c_compiler_available() -> bool:
    """Whether ``setup.py`` can compile here: the C compiler that setuptools would call (``$CC``, else the one
    Python was built with) is on the path. Without one the build leaves everything to the sources."""
    import shlex
    import shutil
    import sysconfig

    command = shlex.split(os.environ.get("CC") or sysconfig.get_config_var("CC") or "")
    return bool(command) and shutil.which(command[0]) is not None


def compiled_files(package_dir: StrPath) -> dict[str, str]:
    """Every module of the package with a compiled file beside its source, listed or not (a file left by an
    older build must not be imported either): ``{module: its compiled file}``. (``os.scandir``, each folder
    once: this runs at every start, where ``os.walk`` cost twice as much and three ``Path.rglob`` several times
    more; each name is tested against all suffixes at once by ``str.endswith`` before the one it has is found.)"""
    package_dir = os.fspath(package_dir)
    found = {}
    suffixes = tuple(sorted(importlib.machinery.EXTENSION_SUFFIXES, key=len, reverse=True))   # the longest first
    folders = [(package_dir, os.path.basename(os.path.normpath(package_dir)))]     # (folder, its module name)
    while folders:
        folder, prefix = folders.pop()
        with os.scandir(folder) as scan:
            entries = list(scan)
        names = {entry.name for entry in entries}
        for entry in entries:
            name = entry.name
            if name.endswith(suffixes):
                stem = name[:-len(next(x for x in suffixes if name.endswith(x)))]
                if stem + ".py" in names:
                    found[f"{prefix}.{stem}"] = entry.path
            elif name != "__pycache__" and entry.is_dir(follow_symlinks=False):   # as os.walk
                folders.append((entry.path, f"{prefix}.{name}"))
    return found


def built_digests(package_dir: StrPath = _PACKAGE_DIR) -> dict[str, str]:
    """The source digests the last build recorded, by module (empty: no build, or an unreadable record)."""
    import json

    try:
        with open(os.path.join(package_dir, MANIFEST), encoding="utf-8") as f:
            built = json.load(f)
    except (OSError, ValueError):
        return {}
    return built if isinstance(built, dict) else {}


def modules_to_load_from_source(package_dir: StrPath = _PACKAGE_DIR) -> tuple[dict[str, str], list[str]]:
    """Which compiled modules must not be used: ``{module: its .py}`` (none, or all of them), and the stale
    ones (edited since the build, or left by an older one) that made it all."""
    present = {m: source_path(m, package_dir) for m in compiled_files(package_dir)}
    if not present:
        return {}, []
    if pure_requested():
        return present, []
    built = built_digests(package_dir)
    stamps = built.get(STAMPS) if isinstance(built.get(STAMPS), dict) else {}
    stale = sorted(m for m, src in present.items()
                   if not (stamps.get(m) == source_stamp(src) and m in built) and built.get(m) != source_digest(src))
    # a listed module the build did not compile (its C compile failed: the extensions are optional)
    stale += sorted(m for m in COMPILED_MODULES if m not in present and os.path.exists(source_path(m, package_dir)))
    # all or none: compiled modules share C types (agent.so reads intentions.Frame's fields directly,
    # see the .pxd files), so one module from source means every module from source
    return (present if stale else {}), stale


class _Guard:
    """The guard on ``sys.meta_path`` (first): before the first compiled module of the package is imported, it runs
    the check (``modules_to_load_from_source``, with one warning naming what is stale); from then on it hands out
    the ``.py`` of every module the check rejected (all or none) and leaves everything else to the finders after it.

    Why at the first compiled module and not at ``import agentspeak``: the check reads the build's record and the
    size and time of every compiled module's source, a short command's whole budget for a few percent (issue 23),
    and a command that imports only plain modules of the package (``faultmas diagnose``: errors, source_text,
    user_cache) imports nothing it could be wrong about. Until then it finds each ``agentspeak.*`` module as the
    path finder after it would, to see whether that is a compiled file (an extension module's loader)."""

    def __init__(self) -> None:
        self.sources: dict[str, str] | None = None     # {module: its .py} once checked

    def find_spec(self, fullname, path=None, target=None):
        if not fullname.startswith("agentspeak."):
            return None
        if self.sources is None:
            spec = importlib.machinery.PathFinder.find_spec(fullname, path, target)
            if spec is None or not isinstance(spec.loader, importlib.machinery.ExtensionFileLoader):
                return spec                          # a plain module (found once: returned, not looked up again)
            self.sources = {}                        # (the check's own imports are not the package's)
            self.sources = _check()
            if fullname not in self.sources:
                return spec
        source = self.sources.get(fullname)
        if source is None:
            return None
        from importlib.util import spec_from_file_location   # only when something runs from source

        return spec_from_file_location(fullname, source)


def _check() -> dict[str, str]:
    """``modules_to_load_from_source``, the stale modules named in one warning: ``{module: its .py}``."""
    sources, stale = modules_to_load_from_source()
    if stale:
        import logging

        logging.getLogger("faultmas.speedups").warning("compiled %s not built from the source on disk (edited since, left by an older build, or "
                    "not compiled by the last one): %s; the interpreter runs from source until you run %s",
                    "module" if len(stale) == 1 else "modules", ", ".join(stale), REBUILD)
    return sources


def install() -> None:
    """Called once by ``agentspeak/__init__.py``, before any compiled module can be imported: puts the guard first
    on ``sys.meta_path`` (``_Guard``; the check itself runs when the first compiled module is looked for)."""
    sys.meta_path.insert(0, _Guard())


def describe() -> str:
    """How the interpreter runs, for benchmark tables and bug reports: compiled or from source (never
    mixed: see ``modules_to_load_from_source``)."""
    loaded = [m for m in COMPILED_MODULES if m in sys.modules]
    compiled = [m for m in loaded if not str(getattr(sys.modules[m], "__file__", "")).endswith(".py")]
    return f"compiled (Cython, {len(compiled)} modules)" if compiled else "pure Python"
