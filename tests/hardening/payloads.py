"""Hostile inputs of the reliability campaign, by name: each one crashed or flooded something once
(issue 22), and each is now refused with a reason. Built by functions: some are megabytes."""
from __future__ import annotations

from agents.transport.envelope import Envelope


def _tell(content: str, sender: str = "alice") -> bytes:
    return Envelope("m", sender, ("bob",), "tell", content).encode()


HOSTILE = {
    # 20,000 nested structures in a 60 KB tell: SIGSEGV of the compiled agent, RecursionError from source
    "deep_structure": lambda: _tell("f(" * 20_000 + "a" + ")" * 20_000),
    # 40,000 nested lists
    "deep_list": lambda: _tell("[" * 40_000 + "]" * 40_000),
    # annotations nested 20,000 deep
    "deep_annotations": lambda: _tell("p" + "[a" * 20_000 + "]" * 20_000),
    # a 20,000-term sum (a left-deep expression tree)
    "long_sum": lambda: _tell("+".join(["X"] * 20_000)),
    # an integer of 5,000 digits (Python's int() refuses more than 4,300)
    "huge_integer": lambda: _tell("n(" + "7" * 5_000 + ")"),
    # a JSON envelope nested 100,000 deep
    "deep_json": lambda: b"[" * 100_000 + b"]" * 100_000,
    # 21,000 tiny bad envelopes in one 63 KB batch (log amplification)
    "bad_batch": lambda: b"{}\n" * 21_000,
}
