"""Reading YAML with line numbers: every model or rule error names file:line of the offending entry.

PyYAML's composer keeps a ``start_mark`` on every node; these helpers walk nodes instead of plain
dicts so that the place of each scalar stays at hand.
"""
from __future__ import annotations

import sys
from pathlib import Path
from typing import NoReturn

import yaml
import yaml.reader
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

from agentspeak.errors import SourceError
from agentspeak.source_text import read_source


class YamlSource:
    """One YAML file: its root node and the means to raise errors that point into it."""

    def __init__(self, path: str | Path, text: str | None = None) -> None:
        self.path = str(path)
        self.text = read_source(path, "YAML file") if text is None else text
        self.lines = self.text.splitlines()
        try:
            self.root = yaml.compose(self.text, Loader=yaml.SafeLoader)
        except yaml.reader.ReaderError as exc:  # a control character (NUL, say): found by the fuzz campaign
            line = self.text.count("\n", 0, exc.position) + 1
            column = exc.position - (self.text.rfind("\n", 0, exc.position) + 1) + 1
            raise SourceError(f"YAML does not allow the character U+{exc.character:04X} here", file=self.path,
                              line=line, column=column) from None
        except RecursionError:  # PyYAML's composer recurses once per level: a list nested 20,000 deep
            raise SourceError(f"nested too deeply (YAML lists or mappings inside each other beyond "
                              f"{sys.getrecursionlimit() // 2} levels)", file=self.path) from None
        except yaml.MarkedYAMLError as exc:
            mark = exc.problem_mark
            line = mark.line + 1 if mark else None
            raise SourceError(f"YAML syntax error: {exc.problem}", file=self.path, line=line,
                              column=mark.column + 1 if mark else None,
                              source_line=self._line(line)) from None
        if self.root is None:
            raise SourceError("empty file", file=self.path, line=1)

    def _line(self, line: int | None) -> str | None:
        if line is None or not 1 <= line <= len(self.lines):
            return None
        return self.lines[line - 1]

    def error(self, node: Node, message: str, column_offset: int | None = None) -> NoReturn:
        """Raise a SourceError at the node (column_offset: 1-based column inside a scalar's text)."""
        line = node.start_mark.line + 1
        column = node.start_mark.column + 1
        if column_offset is not None and isinstance(node, ScalarNode) and node.style in (None, "'", '"'):
            column += column_offset - (0 if node.style is None else -1) - 1
        raise SourceError(message, file=self.path, line=line, column=column, source_line=self._line(line))

    def mapping(self, node: Node, what: str) -> dict[str, tuple[ScalarNode, Node]]:
        """Keys (as text) to (key node, value node); duplicate keys are errors."""
        if not isinstance(node, MappingNode):
            self.error(node, f"{what} must be a mapping")
        out: dict[str, tuple[ScalarNode, Node]] = {}
        for key, value in node.value:
            name = self.scalar(key, f"a key of {what}")
            if name in out:
                self.error(key, f"duplicate key {name!r} in {what}")
            out[name] = (key, value)
        return out

    def sequence(self, node: Node, what: str) -> list[Node]:
        if not isinstance(node, SequenceNode):
            self.error(node, f"{what} must be a list")
        return list(node.value)

    def scalar(self, node: Node, what: str) -> str:
        if not isinstance(node, ScalarNode) or node.value == "" and node.tag.endswith(":null"):
            self.error(node, f"{what} must be a plain value")
        return str(node.value)

    def names(self, node: Node, what: str) -> list[tuple[str, ScalarNode]]:
        """A list of names (``[a, b]``) as (name, node) pairs; duplicates are errors."""
        seen: set[str] = set()
        out = []
        for item in self.sequence(node, what):
            name = self.scalar(item, f"an entry of {what}")
            if name in seen:
                self.error(item, f"{name!r} is listed twice in {what}")
            seen.add(name)
            out.append((name, item))
        return out

    def check_keys(self, entries: dict[str, tuple[ScalarNode, Node]], allowed: tuple[str, ...], what: str) -> None:
        for name, (key, _value) in entries.items():
            if name not in allowed:
                self.error(key, f"unknown key {name!r} in {what}; expected one of: {', '.join(allowed)}")
