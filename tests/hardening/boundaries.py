"""Every input boundary of faultmas as one function ``bytes -> None`` and the errors it may raise: the
project's own located errors. Used by the fuzz tests (``test_fuzz_boundaries``) and the long campaign
(``make campaign``). Anything else raised (or a crash, or a hang) is a defect."""
from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Callable

from agents.transport.envelope import BadMessage, decode
from agents.zenoh_arch import ContentCache
from agentspeak.errors import FaultmasError, SourceError
from agentspeak.mas2j import parse_mas2j
from agentspeak.parser import parse_program_all_errors
from diagnosis.cli import read_observations
from diagnosis.formula import FormulaSyntaxError, parse_formula, to_cnf
from diagnosis.loader import load_model

_SCRATCH = Path(tempfile.mkdtemp(prefix="faultmas-fuzz-"))


def _text(data: bytes) -> str:
    return data.decode("utf-8", "replace")


def asl_program(data: bytes) -> None:
    path = _SCRATCH / "fuzz.asl"
    path.write_bytes(data)
    from agentspeak.source_text import read_source
    program, _errors = parse_program_all_errors(read_source(path), str(path))
    for plan in program.plans:  # what an agent does with a parsed plan first: print and copy it
        str(plan)


def message_content(data: bytes) -> None:
    term = ContentCache().parse(_text(data))
    str(term), hash(term)  # what the agent layer does with a received term: logs and belief base


def envelope(data: bytes) -> None:
    decode(data)


def mas2j_project(data: bytes) -> None:
    parse_mas2j(_text(data), "fuzz.mas2j")


def formula(data: bytes) -> None:
    counter = iter(range(10 ** 9))
    to_cnf(parse_formula(_text(data)), lambda lit: 1 + hash(lit) % 1000, lambda: 2000 + next(counter))


def yaml_model(data: bytes) -> None:
    path = _SCRATCH / "fuzz.yaml"
    path.write_bytes(data)
    load_model(path)


def bench_model(data: bytes) -> None:
    path = _SCRATCH / "fuzz.bench"
    path.write_bytes(data)
    load_model(path)


def observations(data: bytes) -> None:
    path = _SCRATCH / "obs.json"
    path.write_bytes(data)
    read_observations(str(path))


#: name -> (the boundary, the errors it may raise, seeds: valid inputs to mutate)
BOUNDARIES: dict[str, tuple[Callable[[bytes], None], tuple[type[BaseException], ...], list[bytes]]] = {
    "asl": (asl_program, (FaultmasError,), [
        b"!start.\n+!start : true <- .print(\"hi\", 1 + 2 * X); ?b(X); -+c([1,2|T]).\n",
        b"b(1). r(X) :- b(X) & not c(X).\n@l[atomic] +!g(N) : N > 0 <- .send(bob, tell, m(N)); !g(N-1).\n",
        b"+!w <- while (X < 3) { X = X + 1 }; if (a) { .print(a) } else { .fail }.\n"]),
    "content": (message_content, (FaultmasError,), [
        b"pos(3,-4.5,\"x\",a)", b"[a,b|[]]", b"~p(1)[source(self),x(\"s\")]", b"{+!g <- .print(1)}", b"X + 1"]),
    "envelope": (envelope, (BadMessage,), [
        b'{"v":1,"id":"a.1","mas":"m","from":"alice","to":["bob"],"perf":"tell","content":"p(1)"}',
        b'{"v":1,"id":"a.2","mas":"m","from":"bob","to":["alice"],"perf":"tell","content":"x","re":"a.1"}']),
    "mas2j": (mas2j_project, (FaultmasError,), [
        b"MAS rescue {\n  infrastructure: Centralised\n  agents:\n    alice; bob agentArchClass Foo #3;\n"
        b"    carol [beliefs=\"b(1)\", goals=\"g\"];\n  aslSourcePath: \"src\";\n}\n"]),
    "formula": (formula, (FormulaSyntaxError,), [
        b"!AB(left_motor) -> (left_torque <-> commanded_forward)", b"(a & b) | !c -> hz(scan)"]),
    "yaml_model": (yaml_model, (SourceError,), [
        b"system: s\ncomponents: [m]\nobservations: [o]\nvariables: [v]\nbehaviour:\n  - \"!AB(m) -> (v <-> o)\"\n"]),
    "bench_model": (bench_model, (SourceError,), [
        b"INPUT(a)\nINPUT(b)\nOUTPUT(c)\nc = NAND(a, b)\n"]),
    "observations": (observations, (SourceError,), [b'{"o": 1, "p": false}']),
}
