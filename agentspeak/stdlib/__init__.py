"""Jason's standard internal actions and arithmetic functions, one function each, grouped by family.

Importing this package fills ``STDLIB`` and ``FUNCTIONS`` (the explicit list of family modules is below).
"""
from agentspeak.stdlib.registry import (
    FUNCTIONS, STDLIB, IAError, Registry, Suspend, arith_function, internal_action, wrong_arguments,
)
from agentspeak.stdlib import output, lists, strings, bdi, beliefs, plans, communication, system, mas, containers  # noqa: F401
from agentspeak.stdlib import functions  # noqa: F401

__all__ = ["FUNCTIONS", "STDLIB", "IAError", "Registry", "Suspend", "arith_function", "internal_action",
           "wrong_arguments"]
