"""Parsed programs and project files kept between runs: a file run again unchanged is not parsed again.

Why: parsing is most of a short run's start-up. ``import lark`` alone costs about as much CPU as the
interpreter's own start, building the parser and compiling its lexer's regular expressions as much again,
and a 2,000-plan program takes 0.8 s to parse but 0.1 s to load from here. So, as Python keeps ``.pyc``
files, faultmas keeps each parsed file (pickled) in the user's cache directory (``agentspeak.user_cache``)
and a command that finds its file unchanged never imports Lark.

An entry is used only if all of these are exactly what the entry was made from, else the file is parsed
again (and the entry replaced):

* the file's whole text and its name (both kept in the entry and compared; the entry's file name, a CRC of
  them, only finds it);
* what else the parse depended on: the source path, the names of the registered arithmetic functions;
* the interpreter itself: name, size and modification time of every source, grammar and compiled module
  of ``agentspeak`` (an edited grammar, another branch, an upgrade or a rebuild all miss), whether it runs
  compiled, and the Python version.

A program with an ``include`` is not kept (the files it includes would be more text to compare) and neither
is text that does not come from a file (``source_file`` like ``<string>``). The entries are pickles, so this
directory must be the user's own, as for ``.pyc`` files. Nothing here is needed: a damaged or unreadable
entry or a read-only directory only costs the parse. At most ``MAX_ENTRIES`` files are kept.
"""
from __future__ import annotations

import os
import sys
import zlib
from typing import Callable, TypeVar

from agentspeak.program import Program, copy_program
from agentspeak.stdlib.registry import FUNCTIONS, set_program_reader
from agentspeak.user_cache import cache_dir, code_files, write_entry

T = TypeVar("T")

FORMAT = 1
"""Bumped when an entry's layout changes."""
MAX_ENTRIES = 256
SUBDIRECTORY = "parsed"
_CODE_SUFFIXES = (".py", ".lark", ".so", ".pyd", ".pxd")
_MISS = object()
_code_key: tuple | None = None
_PROGRAMS: dict[tuple, Program] = {}
"""This process's programs, so that 100 agents of one file load it once and share its terms."""
_PROGRAMS_MAX = 32


def cached_program(text: str, source_file: str = "<string>", source_path: tuple = ()) -> Program:
    """``agentspeak.parser.parse_program(text, source_file, source_path=...)``, from the cache when the file
    was parsed before; each call gets its own copy (plans hold per-agent labels and flags).
    Raises ``AslSyntaxError`` as the parser does (errors are not kept: the parser reports them again)."""
    key = (text, source_file, tuple(source_path), tuple(sorted(FUNCTIONS.functions)))
    program = _PROGRAMS.get(key)
    if program is None:
        program = cached("program", text, source_file, key[2:], lambda: _parse(text, source_file, key[2]),
                         keep="include" not in text)
        if len(_PROGRAMS) >= _PROGRAMS_MAX:
            _PROGRAMS.clear()
        _PROGRAMS[key] = program
    return copy_program(program)


def _parse(text: str, source_file: str, source_path: tuple = (), namespace: str = "default") -> Program:
    from agentspeak.parser import parse_program
    return parse_program(text, source_file, source_path=source_path, namespace=namespace)


set_program_reader(_parse)   # ``.include`` in an agent whose program came from the cache: the parser, when needed


def cached(kind: str, text: str, source_file: str, extra: tuple, parse: Callable[[], T], keep: bool = True) -> T:
    """``parse()`` (which reads ``text``, the content of ``source_file``), or its result as kept by an earlier
    run for the same ``kind``, text, file, ``extra`` (what else the result depends on) and interpreter."""
    if not keep or source_file.startswith("<"):
        return parse()
    header = (FORMAT, kind, source_file, extra, code_key(), text)
    path = cache_dir() / SUBDIRECTORY / _entry_name(kind, source_file, extra, text)
    value = _load(path, header)
    if value is _MISS:
        value = parse()
        _store(path, header, value)
    return value  # type: ignore[return-value]


def code_key() -> tuple:
    """What identifies this interpreter's code (see the module doc); computed once per process."""
    global _code_key
    if _code_key is None:
        import agentspeak.program as compiled_or_not
        _code_key = (sys.version, compiled_or_not.__file__, package_files(os.path.dirname(os.path.abspath(__file__))))
    return _code_key


def package_files(root: str) -> tuple:
    """(name, size, modification time) of the sources, grammars and compiled modules in ``root`` and ``root/stdlib``."""
    return code_files(root, ("", "stdlib"), _CODE_SUFFIXES)


def _entry_name(kind: str, source_file: str, extra: tuple, text: str) -> str:
    crc = zlib.crc32(text.encode("utf-8", "surrogatepass"), zlib.crc32(repr((kind, source_file, extra)).encode()))
    return f"{kind}-{os.path.basename(source_file)[:40]}-{crc:08x}.pickle"


def _load(path, header: tuple) -> object:
    import pickle
    try:
        with open(path, "rb") as f:
            if pickle.load(f) != header:
                return _MISS
            return pickle.load(f)
    except Exception:  # noqa: BLE001 - missing, damaged, or naming code that is gone: parse instead
        return _MISS


def _store(path, header: tuple, value: object) -> None:
    import pickle
    try:
        data = pickle.dumps(header, pickle.HIGHEST_PROTOCOL) + pickle.dumps(value, pickle.HIGHEST_PROTOCOL)
    except Exception:  # noqa: BLE001 - e.g. a plugin's function that pickle cannot name: not kept, still correct
        return
    write_entry(path, data, MAX_ENTRIES)
