"""Reading a source file as UTF-8 text, with a located error for bytes that are not UTF-8.

Why: ``Path.read_text()`` raises ``UnicodeDecodeError`` (a traceback, no line) for a file saved in
Latin-1 or a binary file given by mistake; every loader of the project (``.asl``, ``.mas2j``, ``.yaml``,
``.bench``, observations ``.json``) reads through here so the user gets ``file:line:column: not UTF-8``.
Not compiled (``agentspeak/_speedups.py``): cold code. No ``pathlib`` (``open``, which takes both): its import was a
tenth of a short ``faultmas diagnose``, which reads its files here (issue 23).
"""
from __future__ import annotations

import os

from agentspeak.errors import SourceError


def read_source(path: str | os.PathLike, what: str = "file") -> str:
    """The text of ``path`` (UTF-8); ``SourceError`` naming file, line and column of the first byte
    that is not UTF-8. ``OSError`` (no such file...) is left to the caller, which knows what it wanted."""
    with open(path, "rb") as f:
        data = f.read()
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        line_start = data.rfind(b"\n", 0, exc.start) + 1
        column = len(data[line_start:exc.start].decode("utf-8", "replace")) + 1
        raise SourceError(f"this {what} is not UTF-8 text (byte 0x{data[exc.start]:02x} cannot be decoded)",
                          file=str(path), line=line, column=column) from None
