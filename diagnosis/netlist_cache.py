"""Compiled netlists kept between runs: a ``.bench`` file diagnosed again unchanged is not parsed and encoded again.

Why: reading a netlist (a regular expression per line, a topological sort) and building its CNF cost about as much
as the whole search of a short ``faultmas diagnose`` on the ISCAS-85 circuits (issue 23). As the parse cache does for
``.asl`` files (``agentspeak/parse_cache.py``), whose conventions this follows, the model built from a file is kept in
the user's cache directory (``agentspeak.user_cache``, subdirectory ``netlists``) and used only if all of these are
exactly what it was made from, else the file is read again and the entry replaced:

* the file's whole text and its absolute path (both kept in the entry and compared; a CRC of the path names the
  entry, one per file);
* the code: name, size and modification time of every module of ``diagnosis`` (an edited encoder, another branch,
  an upgrade all miss), ``FORMAT`` and the Python version.

An entry is written with ``marshal`` (the model is plain tuples, dicts, strings and integers): unlike ``pickle`` it
costs no import. A bad file is reported as before and never kept. Nothing here is needed: a damaged entry or a
read-only directory only costs the parse.
"""
from __future__ import annotations

import marshal
import os
import sys
import zlib

from agentspeak.source_text import read_source
from agentspeak.user_cache import cache_path, code_files, write_entry
from diagnosis.model import SystemModel

FORMAT = 1
"""Bumped when an entry's layout changes."""
SUBDIRECTORY = "netlists"
MAX_ENTRIES = 64
_code_key: tuple | None = None


def cached_netlist_model(path: str) -> SystemModel:
    """``diagnosis.bench.load_bench_model(path)``, from the cache when the file was read before unchanged."""
    text = read_source(path, "netlist")
    where = os.path.abspath(path)
    header = (FORMAT, where, code_key(), text)
    entry = os.path.join(cache_path(), SUBDIRECTORY,
                         f"{os.path.basename(path)[:40]}-{zlib.crc32(os.fsencode(where)):08x}.marshal")
    try:
        with open(entry, "rb") as f:
            kept, fields = marshal.loads(f.read())   # one object: marshal.load from a file reads item by item
        if kept == header:
            return SystemModel(*fields)
    except Exception:  # noqa: BLE001 - missing or damaged (or not this code's layout): read the file again
        pass
    from diagnosis.bench import netlist_model, parse_bench

    model = netlist_model(parse_bench(path, text))
    write_entry(entry, marshal.dumps((header, model.fields())), MAX_ENTRIES)
    return model


def code_key() -> tuple:
    """What identifies the code that builds a model (see the module doc); computed once per process."""
    global _code_key
    if _code_key is None:
        _code_key = (sys.version, code_files(os.path.dirname(os.path.abspath(__file__))))
    return _code_key
