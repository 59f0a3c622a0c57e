"""Jason project files (``.mas2j``): the agents of a MAS, their sources, options and instance counts.

``b b.asl #3;`` declares agents ``b1 b2 b3`` as Jason does; ``[beliefs="next(x)", goals="g"]`` adds
initial beliefs and goals. Infrastructure, environment and classes are recorded (Java classes cannot
run here; the environment name selects a faultmas environment or robot bridge where one exists).
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from agentspeak.lark_loader import lalr_parser  # first: it refuses lark-parser 0.12 with the fix
from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedInput

from agentspeak.errors import AslSyntaxError

_GRAMMAR = Path(__file__).with_name("mas2j.lark")
_PARSER: Lark | None = None


@dataclass
class AgentDecl:
    name: str
    source: str                       # path of the .asl file
    options: dict = field(default_factory=dict)
    instances: int = 0                # 0: a single agent named `name`

    def instance_names(self) -> list[str]:
        if self.instances <= 0:
            return [self.name]
        return [f"{self.name}{i}" for i in range(1, self.instances + 1)]


@dataclass
class MasProject:
    name: str
    agents: list[AgentDecl]
    environment: str | None = None
    infrastructure: str | None = None
    source_paths: list[str] = field(default_factory=list)
    file: str = ""

    def agent_names(self) -> list[str]:
        return [n for a in self.agents for n in a.instance_names()]


def _parser() -> Lark:
    global _PARSER
    if _PARSER is None:
        _PARSER = lalr_parser(_GRAMMAR, maybe_placeholders=True)
    return _PARSER


def parse_mas2j(text: str, file: str = "<mas2j>") -> MasProject:
    try:
        tree = _parser().parse(text)
    except UnexpectedInput as exc:
        lines = text.split("\n")
        line = getattr(exc, "line", 1) or 1
        col = getattr(exc, "column", 1) or 1
        expected = sorted(getattr(exc, "expected", None) or getattr(exc, "allowed", None) or [])
        found = getattr(getattr(exc, "token", None), "value", None)
        msg = f"unexpected {found!r}" if found else "syntax error"
        if expected:
            msg += "; expected one of " + ", ".join(expected[:8])
        raise AslSyntaxError(msg, file, line, col, lines[line - 1] if 0 < line <= len(lines) else None) from None
    base = os.path.dirname(file) if file and not file.startswith("<") else "."
    name = str(tree.children[0])
    project = MasProject(name, [], file=file)
    for section in tree.children[1:]:
        if not isinstance(section, Tree):
            continue
        if section.data == "agents":
            for decl in section.children:
                project.agents.append(_agent(decl))
        elif section.data == "environment":
            project.environment = _class_text(section.children[0])
        elif section.data == "infrastructure":
            project.infrastructure = _class_text(section.children[0])
        elif section.data == "source_path":
            project.source_paths = [str(s)[1:-1] for s in section.children]
    paths = [os.path.join(base, p) for p in project.source_paths] + [base]
    for decl in project.agents:
        decl.source = _find_source(decl.source, paths)
    return project


def _agent(tree: Tree) -> AgentDecl:
    name = str(tree.children[0])
    file_part, options_part = tree.children[1], tree.children[2]
    source = f"{name}.asl"
    if file_part is not None:
        tok = file_part.children[0]
        text = str(tok)
        source = text[1:-1] if tok.type == "STRING" else text
        if not source.endswith(".asl"):
            source += ".asl"
    options = {}
    if options_part is not None:
        for opt in options_part.children:
            key, value = opt.children
            v = str(value)
            options[str(key)] = v[1:-1] if isinstance(value, Token) and value.type == "STRING" else v
    instances = 0
    for child in tree.children[3:]:
        if isinstance(child, Tree) and child.data == "instances":
            instances = int(float(str(child.children[0])))
    return AgentDecl(name, source, options, instances)


def _class_text(tree: Tree) -> str:
    return str(tree.children[0])


def _find_source(source: str, paths: list[str]) -> str:
    if os.path.isabs(source):
        return source
    for p in paths:
        candidate = os.path.join(p, source)
        if os.path.exists(candidate):
            return candidate
    return os.path.join(paths[-1], source)


def load_mas2j(path: str) -> MasProject:
    return parse_mas2j(Path(path).read_text(), path)
