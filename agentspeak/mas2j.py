"""Jason project files (``.mas2j``): the agents of a MAS, their sources, options and instance counts.

``b b.asl #3;`` declares agents ``b1 b2 b3`` as Jason does; ``[beliefs="next(x)", goals="g"]`` adds
initial beliefs and goals. Infrastructure, environment and classes are recorded (Java classes cannot
run here). ``environment: sim`` (any robot bridge's name, with ``"KEY=VALUE"`` arguments as its options)
gives every agent a robot through that bridge: ``agents.environment`` reads ``environment`` and
``environment_args``.
"""
from __future__ import annotations

import os
from pathlib import Path

from typing import TYPE_CHECKING

from agentspeak.errors import AslSyntaxError
from agentspeak.source_text import read_source

if TYPE_CHECKING:
    from lark import Lark, Tree

# Lark is imported where a file is parsed: a project parsed before comes from agentspeak.parse_cache.

#: The most instances one declaration may ask for (``robot #N``): a typo such as ``#99999999999999999999``
#: must be a located error, not a list of names growing to gigabytes.
MAX_INSTANCES = 10_000

_GRAMMAR = Path(__file__).with_name("mas2j.lark")
_PARSER: Lark | None = None


class _Record:
    """Fields compared and shown as a dataclass does them (not ``dataclasses`` itself: its import, with
    ``inspect`` and ``ast``, was a twentieth of a short ``faultmas mas run``, issue 23)."""

    _FIELDS: tuple[str, ...] = ()
    _HIDDEN: tuple[str, ...] = ()        # neither compared nor shown

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(getattr(self, f) == getattr(other, f) for f in self._FIELDS if f not in self._HIDDEN)

    __hash__ = None  # type: ignore[assignment]      # mutable, as the dataclasses were

    def __repr__(self) -> str:
        shown = ", ".join(f"{f}={getattr(self, f)!r}" for f in self._FIELDS if f not in self._HIDDEN)
        return f"{type(self).__name__}({shown})"


class AgentDecl(_Record):
    _FIELDS = ("name", "source", "options", "instances", "token")
    _HIDDEN = ("token",)

    def __init__(self, name: str, source: str, options: dict | None = None, instances: int = 0,
                 token: object = None) -> None:
        self.name = name
        self.source = source              # path of the .asl file
        self.options = {} if options is None else options
        self.instances = instances        # 0: a single agent named `name`
        self.token = token                # the name as written (line, column)

    def instance_names(self) -> list[str]:
        if self.instances <= 0:
            return [self.name]
        return [f"{self.name}{i}" for i in range(1, self.instances + 1)]


class MasProject(_Record):
    _FIELDS = ("name", "agents", "environment", "environment_args", "environment_line", "infrastructure",
               "source_paths", "file", "source_dirs")

    def __init__(self, name: str, agents: list[AgentDecl], environment: str | None = None,
                 environment_args: list[str] | None = None, environment_line: int | None = None,
                 infrastructure: str | None = None, source_paths: list[str] | None = None, file: str = "",
                 source_dirs: list[str] | None = None) -> None:
        self.name = name
        self.agents = agents
        self.environment = environment
        self.environment_args = [] if environment_args is None else environment_args
        """The environment's arguments as written (strings unquoted): ``environment: sim("seed=3")``."""
        self.environment_line = environment_line
        self.infrastructure = infrastructure
        self.source_paths = [] if source_paths is None else source_paths
        self.file = file
        self.source_dirs = [] if source_dirs is None else source_dirs
        """Where includes and ``.create_agent`` look (absolute): each ``aslSourcePath`` entry against the
        working directory (as Jason), then against the project file's folder, then that folder."""

    def agent_names(self) -> list[str]:
        return [n for a in self.agents for n in a.instance_names()]


def _parser() -> Lark:
    global _PARSER
    if _PARSER is None:
        from agentspeak.lark_loader import lalr_parser  # first: it refuses lark-parser 0.12 with the fix
        _PARSER = lalr_parser(_GRAMMAR, maybe_placeholders=True)
    return _PARSER


_WORDS = {"NAME": "a name", "QNAME": "a class name", "FILE_NAME": "a file name (x.asl)", "STRING": "a string",
          "NUMBER": "a number", "$END": "end of file"}


def _in_words(terminal: str) -> str:
    """A grammar terminal as a person names it: ``"agents"``-like keywords and punctuation quoted as written,
    the rest in words (not Lark's names such as ``LSQB`` or ``HASH``)."""
    if terminal in _WORDS:
        return _WORDS[terminal]
    for definition in _parser().terminals:
        if definition.name == terminal and type(definition.pattern).__name__ == "PatternStr":
            return f"'{definition.pattern.value}'"
    return terminal.lower()


def parse_mas2j(text: str, file: str = "<mas2j>") -> MasProject:
    """The project declared by ``text`` (the content of ``file``), its agents' sources found along its source
    path; ``AslSyntaxError`` names the place of a mistake."""
    from agentspeak.parse_cache import cached
    project = cached("mas2j", text, file, (), lambda: _declarations(text, file))
    base = os.path.dirname(file) if file and not file.startswith("<") else "."
    project.source_dirs = source_dirs(project.source_paths, base)   # the file system now, not as it was
    for decl in project.agents:
        decl.source = _find_source(decl.source, project.source_dirs)
    return project


def _declarations(text: str, file: str) -> MasProject:
    """The project as written (sources not yet looked up): what agentspeak.parse_cache keeps."""
    from lark import Tree
    from lark.exceptions import UnexpectedInput
    try:
        tree = _parser().parse(text)
    except UnexpectedInput as exc:
        lines = text.split("\n")
        line = getattr(exc, "line", 1) or 1
        col = getattr(exc, "column", 1) or 1
        expected = sorted({_in_words(t) for t in getattr(exc, "expected", None) or getattr(exc, "allowed", None) or []})
        found = getattr(getattr(exc, "token", None), "value", None)
        msg = f"unexpected {found!r}" if found else "syntax error"
        if expected:
            msg += "; expected " + (expected[0] if len(expected) == 1 else
                                    ", ".join(expected[:-1][:7]) + " or " + expected[-1])
        raise AslSyntaxError(msg, file, line, col, lines[line - 1] if 0 < line <= len(lines) else None) from None
    name = str(tree.children[0])
    project = MasProject(name, [], file=file)
    for section in tree.children[1:]:
        if not isinstance(section, Tree):
            continue
        if section.data == "agents":
            for decl in section.children:
                project.agents.append(_agent(decl, file, text))
        elif section.data == "environment":
            project.environment = _class_text(section.children[0])
            project.environment_args = _class_args(section.children[0])
            project.environment_line = getattr(section.children[0].children[0], "line", None)
        elif section.data == "infrastructure":
            project.infrastructure = _class_text(section.children[0])
        elif section.data == "source_path":
            project.source_paths = [str(s)[1:-1] for s in section.children]
    _check_unique_names(project, file, text)
    for decl in project.agents:
        decl.token = None    # only the check above needs it, and a kept Lark token would need Lark to load
    return project


def _error_at(token: object, message: str, file: str, text: str) -> AslSyntaxError:
    line = getattr(token, "line", None)
    lines = text.split("\n")
    return AslSyntaxError(message, file, line, getattr(token, "column", None),
                          lines[line - 1] if line and 0 < line <= len(lines) else None)


def _check_unique_names(project: MasProject, file: str, text: str) -> None:
    """Two agents of one name (``a`` twice, or ``a #2`` beside ``a1``) would share an inbox: refused."""
    seen: set[str] = set()
    for decl in project.agents:
        for name in decl.instance_names():
            if name in seen:
                raise _error_at(decl.token, f"agent name {name!r} is declared twice (each agent needs its own name)",
                                file, text)
            seen.add(name)


def source_dirs(entries: list[str], base: str) -> list[str]:
    """The folders of an ``aslSourcePath``, absolute: Jason reads a relative entry against the working
    directory; an entry found only beside the project file is taken from there (what users of earlier
    faultmas versions wrote), and the project's folder comes last."""
    out: list[str] = []
    for entry in entries:
        for candidate in ([entry] if os.path.isabs(entry) else [entry, os.path.join(base, entry)]):
            if os.path.isdir(candidate):
                out.append(os.path.abspath(candidate))
                break
    out.append(os.path.abspath(base))
    return list(dict.fromkeys(out))


def _agent(tree: Tree, file: str = "<mas2j>", text: str = "") -> AgentDecl:
    from lark import Token, Tree
    name = str(tree.children[0])
    file_part, options_part = tree.children[1], tree.children[2]
    source = f"{name}.asl"
    if file_part is not None:
        tok = file_part.children[0]
        written = str(tok)
        source = written[1:-1] if tok.type == "STRING" else written
        if not source.endswith(".asl"):
            source += ".asl"
        if "\0" in source:
            raise _error_at(tok, "a NUL character in the agent's source file name", file, text)
    options = {}
    if options_part is not None:
        for opt in options_part.children:
            key, value = opt.children
            v = str(value)
            options[str(key)] = _unescape(v[1:-1]) if isinstance(value, Token) and value.type == "STRING" else v
    instances = 0
    for child in tree.children[3:]:
        if isinstance(child, Tree) and child.data == "instances":
            count = child.children[0]
            try:
                instances = int(float(str(count)))
            except (ValueError, OverflowError):
                instances = MAX_INSTANCES + 1
            if not 0 <= instances <= MAX_INSTANCES:
                raise _error_at(count, f"instance count {str(count)[:30]} is out of range (1 to {MAX_INSTANCES})",
                                file, text)
    return AgentDecl(name, source, options, instances, token=tree.children[0])


def _unescape(text: str) -> str:
    """A string option's escapes as Java reads them: ``\\"`` is ``"``, ``\\\\`` is ``\\``."""
    out = []
    i = 0
    while i < len(text):
        ch = text[i]
        if ch == "\\" and i + 1 < len(text):
            nxt = text[i + 1]
            out.append({"n": "\n", "t": "\t"}.get(nxt, nxt))
            i += 2
            continue
        out.append(ch)
        i += 1
    return "".join(out)


def _class_text(tree: Tree) -> str:
    return str(tree.children[0])


def _class_args(tree: Tree) -> list[str]:
    from lark import Token
    """A class definition's arguments as text (a string's quotes and escapes removed)."""
    return [_unescape(str(arg)[1:-1]) if isinstance(arg, Token) and arg.type == "STRING" else str(arg)
            for arg in tree.children[1:] if arg is not None]


def _find_source(source: str, paths: list[str]) -> str:
    if os.path.isabs(source):
        return source
    for p in paths:
        candidate = os.path.join(p, source)
        if os.path.exists(candidate):
            return candidate
    return os.path.join(paths[-1], source)


def load_mas2j(path: str) -> MasProject:
    return parse_mas2j(read_source(path, "project file"), path)
