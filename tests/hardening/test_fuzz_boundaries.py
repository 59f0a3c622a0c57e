"""The fuzzing campaign of issue 22: every input boundary (``boundaries.BOUNDARIES``) gets inputs mutated
from valid seeds (bytes flipped, spans cut or repeated thousands of times, brackets nested, grammar
characters sprinkled) and must answer each with the project's own located error or not at all: never
another exception, never a crash (the C stack), never a hang (pytest-timeout bounds every test).

Profiles (``FAULTMAS_FUZZ_PROFILE``): ``short`` in ``make test`` (seconds), ``campaign`` in ``make campaign``
(``FAULTMAS_FUZZ_EXAMPLES`` per boundary, 20,000 by default). The corpus of inputs that once failed is
replayed in every profile (``corpus/``, file name = the defect, extension = the boundary)."""
from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.hardening.boundaries import BOUNDARIES

CORPUS = Path(__file__).resolve().parent / "corpus"
PROFILE = os.environ.get("FAULTMAS_FUZZ_PROFILE", "short")
EXAMPLES = {"short": 40, "campaign": int(os.environ.get("FAULTMAS_FUZZ_EXAMPLES", "20000"))}[PROFILE]
BY_EXTENSION = {".asl": "asl", ".mas2j": "mas2j", ".txt": None, ".json": None, ".yaml": "yaml_model", ".npy": "depth"}
CORPUS_BOUNDARY = {"deep_content.txt": "content", "duplicate_from.json": "envelope",
                   "huge_integer_content.txt": "content", "huge_integer_observation.json": "observations",
                   "deep_json.json": "observations", "deep_formula.txt": "formula",
                   "huge_window_observers.yaml": "observer_config", "operator_chain_formula.txt": "content",
                   "operator_chain_annotation.txt": "content"}
GRAMMAR_BYTES = b"()[]{}<>!?~+-*/=&|:;.,\"'\\@#$%^_ \n\t0123456789aXzAB\x00\xe9\xff"


@st.composite
def mutated(draw, seeds: list[bytes]) -> bytes:
    data = bytearray(draw(st.sampled_from(seeds)))
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["flip", "insert", "cut", "repeat", "nest", "grammar"]))
        at = draw(st.integers(0, len(data)))
        if kind == "flip" and data:
            data[min(at, len(data) - 1)] = draw(st.integers(0, 255))
        elif kind == "insert":
            data[at:at] = draw(st.binary(max_size=16))
        elif kind == "cut":
            del data[at:at + draw(st.integers(1, 32))]
        elif kind == "repeat":  # a span thousands of times: long chains, long lists, many operators
            span = bytes(data[at:at + draw(st.integers(1, 8))]) or b"("
            data[at:at] = span * draw(st.sampled_from([2, 50, 3000, 30000]))
        elif kind == "nest":  # deep nesting of one bracket kind around the rest
            opener, closer = draw(st.sampled_from([(b"f(", b")"), (b"[", b"]"), (b"(", b")"), (b"{", b"}"),
                                                   (b"!", b""), (b"not ", b""), (b"- ", b"")]))
            depth = draw(st.sampled_from([10, 250, 5000, 40000]))
            data[at:at] = opener * depth
            data.extend(closer * depth)
        else:
            data[at:at] = bytes(draw(st.lists(st.sampled_from(GRAMMAR_BYTES), max_size=12)))
    return bytes(data)


def _check(name: str, data: bytes) -> None:
    boundary, allowed, _seeds = BOUNDARIES[name]
    try:
        boundary(data)
    except allowed:
        pass  # refused with the project's own error: the property holds


@pytest.mark.timeout(600 if PROFILE == "short" else 24 * 3600)
@pytest.mark.parametrize("name", sorted(BOUNDARIES))
def test_every_boundary_answers_mutated_input_with_its_own_errors_only(name):
    seeds = BOUNDARIES[name][2]

    @settings(max_examples=EXAMPLES, deadline=None, database=None, derandomize=PROFILE == "short",
              suppress_health_check=list(HealthCheck))
    @given(mutated(seeds))
    def fuzz(data: bytes) -> None:
        _check(name, data)

    fuzz()


@pytest.mark.parametrize("path", sorted(CORPUS.iterdir()), ids=lambda p: p.name)
def test_the_corpus_of_found_inputs_is_refused_with_the_projects_errors(path):
    name = CORPUS_BOUNDARY.get(path.name) or BY_EXTENSION[path.suffix]
    _check(name, path.read_bytes())
