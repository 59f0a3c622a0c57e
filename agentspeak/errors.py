"""Exceptions shared by every faultmas layer.

One root, ``FaultmasError``, so a caller can catch everything the framework raises on purpose; narrow
subclasses that also derive from the builtin a caller would already catch (``SyntaxError``,
``ValueError``) and that carry the place (file, line, column) of the bad input.
"""
from __future__ import annotations


class FaultmasError(Exception):
    """Root of every error faultmas raises on purpose."""


class SourceError(FaultmasError, ValueError):
    """Bad input read from a file: carries where it is and quotes it."""

    def __init__(self, message: str, file: str | None = None, line: int | None = None,
                 column: int | None = None, source_line: str | None = None) -> None:
        self.message = message
        self.file = file
        self.line = line
        self.column = column
        self.source_line = source_line
        super().__init__(self.format())

    def location(self) -> str:
        parts = [self.file or "<input>"]
        if self.line is not None:
            parts.append(str(self.line))
            if self.column is not None:
                parts.append(str(self.column))
        return ":".join(parts)

    def format(self) -> str:
        text = f"{self.location()}: {self.message}"
        if self.source_line is not None and self.column is not None:
            caret = " " * (max(self.column, 1) - 1) + "^"
            text += f"\n    {self.source_line.rstrip()}\n    {caret}"
        return text


class AslSyntaxError(SourceError, SyntaxError):
    """An AgentSpeak (.asl) or project (.mas2j) file that does not parse."""

    def __str__(self) -> str:  # SyntaxError has its own __str__; keep ours
        return self.format()
