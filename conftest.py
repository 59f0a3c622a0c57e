"""Imports the interpreter package before pytest binds the name ``agentspeak`` to ``tests/agentspeak``
(``--import-mode=importlib``): otherwise ``agentspeak/__init__.py`` never runs, its submodules are found
directly by the editable install, and ``FAULTMAS_PURE_PYTHON=1`` or a stale compiled build go unnoticed."""
import agentspeak  # noqa: F401
