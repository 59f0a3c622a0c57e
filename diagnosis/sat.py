"""The SAT solvers of the diagnoser: python-sat's, made without importing ``pysat.solvers`` for Glucose 4.

Why: ``import pysat.solvers`` also imports ``pysat.formula`` (with ``decimal``, ``bz2``, ``gzip``, ``lzma``
and a compiled formula module), ``pysat.engines`` and ``tempfile``, about 77M instructions, more than the
whole diagnosis of most ISCAS-85 circuits and a third of a short ``faultmas diagnose`` (issue 23). The
solver itself lives in python-sat's compiled extension ``pysolvers`` (11M to load); ``pysat.solvers.Glucose4``
is a thin class over its ``glucose41_*`` functions. ``Glucose4`` below makes exactly the calls that class
makes, for the methods the diagnoser uses, so the solving is python-sat's own.

``make_solver(name)`` gives that class for ``glucose4`` when the extension has those functions (the python-sat
this project pins does; ``tests/diagnosis/test_sat.py`` compares it with ``pysat.solvers.Glucose4``), and
``pysat.solvers.Solver`` for every other name or an extension without them: the rest of python-sat
(cardinality encodings, RC2) is imported where it is used.
"""
from __future__ import annotations

import threading
from collections.abc import Iterable, Sequence

_GLUCOSE = ("glucose41_new", "glucose41_add_cl", "glucose41_solve", "glucose41_solve_lim", "glucose41_model",
            "glucose41_core", "glucose41_setphases", "glucose41_interrupt", "glucose41_clearint", "glucose41_del")


class Glucose4:
    """Glucose 4.1, the calls of ``pysat.solvers.Glucose4`` (the subset the diagnoser uses: clauses, solving
    under assumptions with a time limit's interrupt, model, core, phases)."""

    def __init__(self, bootstrap_with: Iterable[Sequence[int]] = ()) -> None:
        import pysolvers

        self._api = pysolvers
        self.glucose = pysolvers.glucose41_new()
        self.status: bool | None = None
        self.append_formula(bootstrap_with)

    def __enter__(self) -> "Glucose4":
        return self

    def __exit__(self, *exc: object) -> None:
        self.delete()

    def __del__(self) -> None:
        self.delete()

    def delete(self) -> None:
        if getattr(self, "glucose", None):     # also from __del__ of an instance whose __init__ failed
            self._api.glucose41_del(self.glucose)
            self.glucose = None

    def add_clause(self, clause: Sequence[int]) -> None:
        if self._api.glucose41_add_cl(self.glucose, clause) is False:
            self.status = False

    def append_formula(self, clauses: Iterable[Sequence[int]]) -> None:
        add, solver = self._api.glucose41_add_cl, self.glucose
        for clause in clauses:
            if add(solver, clause) is False:
                self.status = False

    def solve(self, assumptions: Sequence[int] = ()) -> bool:
        # the last argument tells the extension it may install its SIGINT handler (main thread only)
        self.status = self._api.glucose41_solve(self.glucose, assumptions,
                                                int(threading.current_thread() is threading.main_thread()))
        return self.status

    def solve_limited(self, assumptions: Sequence[int] = (), expect_interrupt: bool = False) -> bool | None:
        self.status = self._api.glucose41_solve_lim(self.glucose, assumptions,
                                                    int(threading.current_thread() is threading.main_thread()),
                                                    int(expect_interrupt))
        return self.status

    def get_model(self) -> list[int] | None:
        if self.status is True:
            model = self._api.glucose41_model(self.glucose)
            return model if model is not None else []
        return None

    def get_core(self) -> list[int] | None:
        return self._api.glucose41_core(self.glucose) if self.status is False else None

    def set_phases(self, literals: Sequence[int] = ()) -> None:
        self._api.glucose41_setphases(self.glucose, literals)

    def interrupt(self) -> None:
        if self.glucose:
            self._api.glucose41_interrupt(self.glucose)

    def clear_interrupt(self) -> None:
        if self.glucose:
            self._api.glucose41_clearint(self.glucose)


def make_solver(name: str, bootstrap_with: Iterable[Sequence[int]] = ()) -> "Glucose4":
    """A python-sat solver by its python-sat name (``glucose4``, ``cadical195``, ...), loaded with the clauses."""
    if name in ("glucose4", "glucose41", "g4", "g41") and _has_glucose():
        return Glucose4(bootstrap_with)
    from pysat.solvers import Solver

    return Solver(name=name, bootstrap_with=[list(c) for c in bootstrap_with])


_glucose: bool | None = None


def _has_glucose() -> bool:
    global _glucose
    if _glucose is None:
        try:
            import pysolvers
        except ImportError:
            _glucose = False
        else:
            _glucose = all(hasattr(pysolvers, f) for f in _GLUCOSE)
    return _glucose
