"""The registries of internal actions (``.name`` -> function, with arity and a manual line) and of
arithmetic functions (``math.max`` -> function usable inside expressions, see the end of this module).

An internal action is a plain function ``f(ctx, *args)`` decorated with ``@internal_action``.
``args`` are the call's arguments with the intention's bindings applied (variables that are still
unbound stay ``Var``). The function may:

* return ``True``/``None`` (success) or ``False`` (failure, error ``ia_failed``);
* be a generator (or return an iterator): each ``yield`` is one solution (bind with ``ctx.unify``), used for backtracking
  in contexts and ``for`` loops; in a plan body the first solution is taken;
* return ``Suspend(...)`` to suspend only the calling intention until a result arrives (an awaited
  ``concurrent.futures.Future``, a timer, an event) - the agent's other intentions go on;
* raise ``IAError(error, message)`` to fail with specific Jason error annotations
  (``wrong_arguments`` for bad arguments).

Third parties add actions with the same decorator on their own ``Registry`` or on ``STDLIB``
through the ``faultmas.internal_actions`` entry-point group (a module imported on first use).
"""
from __future__ import annotations

import threading
from collections import namedtuple
from concurrent.futures import Future
from typing import Any, Callable

# Plain classes and named tuples, not dataclasses: importing ``dataclasses`` is a noticeable part of a hello
# world's start-up (issue 23).

from agentspeak.errors import FaultmasError
from agentspeak.terms import ArithmeticError_, normalise_number, to_str


class IAError(FaultmasError):
    """An internal action failed on purpose: ``error`` becomes the ``error(...)`` annotation."""

    def __init__(self, error: str, message: str, annots: tuple = ()) -> None:
        super().__init__(message)
        self.error = error
        self.message = message
        self.annots = annots  # further annotations for the failure event (``.fail(why(x))``)


def yields_solutions(result: Any) -> bool:
    """Did the action return solutions (a generator, or any iterator)? Not ``isinstance(result,
    types.GeneratorType)``: a generator of a compiled module (agentspeak/_speedups.py) is Cython's own
    type, and taking it for a plain success would never bind ``X`` in ``.member(X, L)``."""
    return hasattr(type(result), "__next__")


def wrong_arguments(message: str) -> IAError:
    return IAError("wrong_arguments", message)


class Suspend:
    """Returned by an internal action to suspend the calling intention.

    ``future``: resume when it resolves; ``on_result(ctx, value) -> bool`` decides success (and may
    bind with ``ctx.unify``). ``timeout`` (seconds) fails or calls ``on_timeout(ctx) -> bool``.
    ``until`` (a zero-argument callable) is re-checked after each reasoning cycle.
    ``event`` (a Trigger) resumes when a matching event is posted. ``term``: why, as a term
    (``.suspended(G, R)`` gives it; Jason's ``wait(W)[time(T)]`` for ``.wait``). ``answer_waiting``: for an
    ask, is an answer sent by this (monotonic) deadline still unread in the mailbox? Then the timeout waits
    for it to be read. ``on_drop()``: the intention was dropped while suspended here (what the action keeps for
    its resumption can go).
    """

    def __init__(self, future: Future | None = None, on_result: Callable[[Any, Any], bool] | None = None,
                 timeout: float | None = None, on_timeout: Callable[[Any], bool] | None = None,
                 until: Callable[[], bool] | None = None, event: Any = None, reason: str = "suspended",
                 on_event: Callable[[Any, Any], bool] | None = None, term: Any = None,
                 answer_waiting: Callable[[float], bool] | None = None,
                 on_drop: Callable[[], None] | None = None) -> None:
        self.future, self.on_result, self.timeout, self.on_timeout = future, on_result, timeout, on_timeout
        self.until, self.event, self.reason, self.on_event, self.term = until, event, reason, on_event, term
        self.answer_waiting, self.on_drop = answer_waiting, on_drop

    def __repr__(self) -> str:
        return (f"Suspend(future={self.future!r}, timeout={self.timeout!r}, event={self.event!r}, "
                f"reason={self.reason!r}, term={self.term!r})")


class InternalActionSpec(namedtuple("InternalActionSpec", "name function min_args max_args doc")):
    __slots__ = ()


class Registry:
    """Internal actions by AgentSpeak name (with the leading dot)."""

    def __init__(self, actions: dict[str, InternalActionSpec] | None = None) -> None:
        self.actions: dict[str, InternalActionSpec] = {} if actions is None else actions
        self._extensions_loaded = False

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

_program_reader: Callable[[str, str], Any] | None = None


def set_program_reader(reader: Callable[[str, str], Any]) -> None:
    """``agentspeak.parser`` gives ``parse_program`` here when imported, so that ``.include`` can read a file
    without the standard library importing the parser (which imports the standard library: a cycle)."""
    global _program_reader
    _program_reader = reader


def read_program(text: str, file: str, namespace: str = "default") -> Any:
    """Parse AgentSpeak text with the parser registered by ``agentspeak.parser`` (into a name space: a module)."""
    if _program_reader is None:
        raise IAError("no AgentSpeak parser loaded (import agentspeak.parser)")
    if namespace != "default":
        return _program_reader(text, file, namespace=namespace)
    return _program_reader(text, file)
internal_action = STDLIB.internal_action


# ---------------------------------------------------------------------- arithmetic functions
class FunctionError(ArithmeticError_):
    """A function got arguments it cannot compute with: the formula using it fails."""


class _CurrentAgent(threading.local):
    """The agent whose reasoning cycle runs in this thread (set by the runtime at each turn):
    functions such as ``.count`` read its belief base; the others never look."""

    agent: Any = None


CURRENT = _CurrentAgent()


class FunctionSpec(namedtuple("FunctionSpec", "name function arities unground_ok needs_agent doc",
                              defaults=(False, False, ""))):
    """One arithmetic function: ``function(*args)`` (or ``function(agent, *args)`` when
    ``needs_agent``) returns a number or raises ``FunctionError``. ``arities`` are the argument
    counts it accepts (None: any); a literal with another count is not this function (Jason's
    ``checkArity``). ``unground_ok``: evaluated even with unbound variables (``.count(p(_))``)."""

    __slots__ = ()

    def accepts(self, arity: int) -> bool:
        return self.arities is None or arity in self.arities

    def __reduce__(self) -> tuple:
        # Pickled by name (agentspeak/parse_cache.py): a registered function is the registry's own object
        # again on load (its Python function may be a closure, which pickle cannot write); a rule function
        # (``register_function``) is made again from its name, arity and predicate.
        remake = getattr(self.function, "remake", None)     # (callable, args) set by the maker of a closure
        if remake is not None:
            return remake
        if FUNCTIONS.functions.get(self.name) is self:
            return (registered_function, (self.name,))
        return (FunctionSpec, (self.name, self.function, self.arities, self.unground_ok, self.needs_agent, self.doc))

    def evaluate(self, args: tuple) -> int | float | None:
        """The value for resolved ``args``; a failure names the call and why. None when the
        function needs an agent and none runs in this thread (a belief being parsed)."""
        try:
            if self.needs_agent:
                agent = CURRENT.agent
                if agent is None:
                    return None
                value = self.function(agent, *args)
            else:
                value = self.function(*args)
        except FunctionError as exc:
            raise FunctionError(f"{_call_text(self.name, args)}: {exc}") from None
        except (TypeError, ValueError, OverflowError) as exc:
            raise FunctionError(f"{_call_text(self.name, args)}: {exc}") from None
        if type(value) is not int and type(value) is not float:
            raise FunctionError(f"{_call_text(self.name, args)} gave {to_str(value)}, not a number")
        return normalise_number(value)


def _call_text(name: str, args: tuple) -> str:
    return name + ("(" + ",".join(to_str(a) for a in args) + ")" if args else "")


class FunctionRegistry:
    """Arithmetic functions by AgentSpeak name (``math.max``, ``.count``). The parser turns a
    literal into a function call when its name and arity are registered here (Jason decides at
    parse time too), so register before parsing."""

    def __init__(self, functions: dict[str, FunctionSpec] | None = None) -> None:
        self.functions: dict[str, FunctionSpec] = {} if functions is None else functions

    def register(self, spec: FunctionSpec) -> None:
        if "." not in spec.name:
            raise ValueError(f"a function name has a dot: {spec.name!r}")
        self.functions[spec.name] = spec

    def get(self, name: str, arity: int) -> FunctionSpec | None:
        spec = self.functions.get(name)
        return spec if spec is not None and spec.accepts(arity) else None

    def arith_function(self, name: str, args: int | tuple[int, ...] | None = 1, unground: bool = False,
                       agent: bool = False):
        """Decorator: ``@arith_function("math.max", args=(1, 2))``; ``agent=True`` passes the
        running agent first; ``unground=True`` evaluates with unbound variables in the arguments."""
        arities = (args,) if isinstance(args, int) else args

        def decorate(function: Callable) -> Callable:
            doc = (function.__doc__ or "").strip().split("\n")[0]
            self.register(FunctionSpec(name, function, arities, unground, agent, doc))
            return function
        return decorate

    def names(self) -> list[str]:
        return sorted(self.functions)


FUNCTIONS = FunctionRegistry()


def registered_function(name: str) -> FunctionSpec:
    """The function registered under ``name`` (KeyError if none: a pickle naming it is then unusable)."""
    return FUNCTIONS.functions[name]
arith_function = FUNCTIONS.arith_function
