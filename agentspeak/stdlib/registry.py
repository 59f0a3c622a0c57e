"""The one registry of internal actions: ``.name`` -> function, with arity and a manual line.

An internal action is a plain function ``f(ctx, *args)`` decorated with ``@internal_action``.
``args`` are the call's arguments with the intention's bindings applied (variables that are still
unbound stay ``Var``). The function may:

* return ``True``/``None`` (success) or ``False`` (failure, error ``ia_failed``);
* be a generator: each ``yield`` is one solution (bind with ``ctx.unify``), used for backtracking
  in contexts and ``for`` loops; in a plan body the first solution is taken;
* return ``Suspend(...)`` to suspend only the calling intention until a result arrives (an awaited
  ``concurrent.futures.Future``, a timer, an event) - the agent's other intentions go on;
* raise ``IAError(error, message)`` to fail with specific Jason error annotations
  (``wrong_arguments`` for bad arguments).

Third parties add actions with the same decorator on their own ``Registry`` or on ``STDLIB``
through the ``faultmas.internal_actions`` entry-point group (a module imported on first use).
"""
from __future__ import annotations

from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any, Callable

from agentspeak.errors import FaultmasError


class IAError(FaultmasError):
    """An internal action failed on purpose: ``error`` becomes the ``error(...)`` annotation."""

    def __init__(self, error: str, message: str, annots: tuple = ()) -> None:
        super().__init__(message)
        self.error = error
        self.message = message
        self.annots = annots  # further annotations for the failure event (``.fail(why(x))``)


def wrong_arguments(message: str) -> IAError:
    return IAError("wrong_arguments", message)


@dataclass
class Suspend:
    """Returned by an internal action to suspend the calling intention.

    ``future``: resume when it resolves; ``on_result(ctx, value) -> bool`` decides success (and may
    bind with ``ctx.unify``). ``timeout`` (seconds) fails or calls ``on_timeout(ctx) -> bool``.
    ``until`` (a zero-argument callable) is re-checked after each reasoning cycle.
    ``event`` (a Trigger) resumes when a matching event is posted.
    """

    future: Future | None = None
    on_result: Callable[[Any, Any], bool] | None = None
    timeout: float | None = None
    on_timeout: Callable[[Any], bool] | None = None
    until: Callable[[], bool] | None = None
    event: Any = None
    reason: str = "suspended"
    on_event: Callable[[Any, Any], bool] | None = None


@dataclass(frozen=True)
class InternalActionSpec:
    name: str
    function: Callable
    min_args: int
    max_args: int | None
    doc: str


@dataclass
class Registry:
    """Internal actions by AgentSpeak name (with the leading dot)."""

    actions: dict[str, InternalActionSpec] = field(default_factory=dict)
    _extensions_loaded: bool = False

    def register(self, name: str, function: Callable, min_args: int = 0, max_args: int | None = None) -> None:
        if not name.startswith(".") and "." not in name:
            raise ValueError(f"an internal action name has a dot: {name!r}")
        doc = (function.__doc__ or "").strip().split("\n")[0]
        self.actions[name] = InternalActionSpec(name, function, min_args, max_args, doc)

    def get(self, name: str) -> InternalActionSpec | None:
        spec = self.actions.get(name)
        if spec is None and not self._extensions_loaded:
            self.load_extensions()
            spec = self.actions.get(name)
        return spec

    def load_extensions(self) -> None:
        """Import the modules named in the ``faultmas.internal_actions`` entry-point group once.

        Each such module registers its actions on ``STDLIB`` with the decorator when imported; this
        keeps the interpreter free of imports of higher layers (the diagnoser, robot bridges).
        """
        self._extensions_loaded = True
        from importlib.metadata import entry_points
        for ep in entry_points(group="faultmas.internal_actions"):
            try:
                ep.load()
            except Exception as exc:  # a broken plug-in must not take the interpreter down
                import logging
                logging.getLogger("faultmas.agentspeak").warning(
                    "internal-action plug-in %s (%s) failed to load: %s", ep.name, ep.value, exc)

    def internal_action(self, name: str, args: int | tuple[int, int | None] = (0, None)):
        """Decorator: ``@internal_action(".length", args=2)`` or ``args=(1, 3)``."""
        lo, hi = (args, args) if isinstance(args, int) else args

        def decorate(function: Callable) -> Callable:
            self.register(name, function, lo, hi)
            return function
        return decorate

    def names(self) -> list[str]:
        return sorted(self.actions)


STDLIB = Registry()
internal_action = STDLIB.internal_action
