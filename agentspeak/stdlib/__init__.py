"""Jason's standard internal actions, one function each, grouped by family.

Importing this package fills ``STDLIB`` (the explicit list of family modules is below).
"""
from agentspeak.stdlib.registry import STDLIB, IAError, Registry, Suspend, internal_action, wrong_arguments
from agentspeak.stdlib import output, lists, strings, bdi, beliefs, plans, communication, system  # noqa: F401

__all__ = ["STDLIB", "IAError", "Registry", "Suspend", "internal_action", "wrong_arguments"]
