"""Time, randomness, waiting and the MAS: time, date, nano_time, random, wait, stopMAS, include."""
from __future__ import annotations

import random as _random
import time        # not datetime: its import is a noticeable part of a hello world's start (issue 23)

from agentspeak.program import PlanTerm
from agentspeak.stdlib.registry import IAError, Suspend, internal_action, wrong_arguments
from agentspeak.terms import Literal, Var, normalise_number


@internal_action(".time", args=(3, 4))
def time_(ctx, h, m, s, ms=None):
    seconds = time.time()
    now = time.localtime(seconds)
    ok = ctx.unify(h, now.tm_hour) and ctx.unify(m, now.tm_min) and ctx.unify(s, now.tm_sec)
    return ok and (ms is None or ctx.unify(ms, int(seconds % 1 * 1000)))


@internal_action(".date", args=3)
def date(ctx, y, m, d):
    today = time.localtime()
    return ctx.unify(y, today.tm_year) and ctx.unify(m, today.tm_mon) and ctx.unify(d, today.tm_mday)


@internal_action(".nano_time", args=1)
def nano_time(ctx, t):
    return ctx.unify(t, time.perf_counter_ns())


class JavaRandom(_random.Random):
    """``java.util.Random``'s generator (a 48-bit linear congruential one), so that a seeded program
    (``.set_random_seed(20)``) draws the numbers it draws under Jason."""

    _MULT, _MASK = 0x5DEECE66D, (1 << 48) - 1

    def seed(self, a=None, version=2) -> None:  # noqa: D102 - random.Random's signature
        if a is None:
            a = time.time_ns()
        self._seed = (int(a) ^ self._MULT) & self._MASK

    def _next(self, bits: int) -> int:
        self._seed = (self._seed * self._MULT + 0xB) & self._MASK
        r = self._seed >> (48 - bits)
        return r - (1 << 32) if r >= 1 << 31 else r  # Java's (int) cast

    def random(self) -> float:
        return ((self._next(26) << 27) + self._next(27)) * (1.0 / (1 << 53))

    def getrandbits(self, k: int) -> int:
        out, got = 0, 0
        while got < k:
            out |= (self._next(32) & 0xFFFFFFFF) << got
            got += 32
        return out & ((1 << k) - 1)

    def next_int(self, bound: int) -> int:
        """Java's ``nextInt(bound)``."""
        if bound & -bound == bound:
            return (bound * self._next(31)) >> 31
        while True:
            bits = self._next(31)
            val = bits % bound
            if bits - val + (bound - 1) < (1 << 31):
                return val

    def choice(self, seq):
        return seq[self.next_int(len(seq))]

    def getstate(self):
        return self._seed

    def setstate(self, state) -> None:
        self._seed = state


def _rng(agent) -> _random.Random:
    rng = getattr(agent, "_rng", None)
    if rng is None:
        rng = agent._rng = JavaRandom()
    return rng


@internal_action(".random", args=(1, 3))
def random(ctx, x, n=None, m=None):
    """``.random(X)``: a number in [0, 1); ``.random(X, N)``: backtracks over N such numbers (0: no end);
    ``.random(List, X[, N])``: a random element of List (N of them; 0: no end). As Jason 3."""
    from agentspeak.terms import Cons, NIL, list_items
    rng = _rng(ctx.agent)
    if n is None:  # not a generator here: a function with ``yield`` would never bind X
        return ctx.unify(x, rng.random())
    if isinstance(x, Cons) or x is NIL:
        items = list_items(x)
        if not items:
            return False
        count = 1 if m is None else m
        if not isinstance(count, (int, float)):
            raise wrong_arguments(".random(List, X, N): N is a number")
        return _random_values(ctx, lambda: rng.choice(items), n, int(count))
    if not isinstance(n, (int, float)):
        raise wrong_arguments(".random(X, N): N is a number (or write .random(List, X))")
    return _random_values(ctx, rng.random, x, int(n))


def _random_values(ctx, draw, x, n: int):
    from agentspeak.unify import undo
    i = 0
    while n == 0 or i < n:
        i += 1
        mark = len(ctx.trail)
        if ctx.unify(x, draw()):
            yield
        undo(ctx.b, ctx.trail, mark)


@internal_action(".set_random_seed", args=1)
def set_random_seed(ctx, seed):
    _rng(ctx.agent).seed(seed)


@internal_action(".wait", args=(1, 3))
def wait(ctx, what, timeout=None, elapsed=None):
    """``.wait(Ms)``, ``.wait({Event}[, Ms[, Elapsed]])`` or ``.wait(Condition[, Ms[, Elapsed]])``.
    With two arguments a timeout fails the goal; with three it does not (Elapsed says how long)."""
    clock = ctx.agent.clock  # the agent's time (its environment's clock, if it has one): Elapsed counts in it
    started = clock()
    from agentspeak.terms import Literal
    if isinstance(what, (int, float)):
        return Suspend(timeout=max(0.0, what / 1000.0), on_timeout=lambda c: True, reason="wait",
                       term=Literal("wait", (what,), (Literal("time", (what,)),)))
    seconds = None
    if timeout is not None:
        if not isinstance(timeout, (int, float)):
            raise wrong_arguments(".wait: the timeout is a number of milliseconds")
        seconds = timeout / 1000.0

    def done(c) -> bool:
        return elapsed is None or c.unify(elapsed, normalise_number(round((clock() - started) * 1000)))

    on_timeout = None
    if seconds is not None:
        on_timeout = (lambda c: done(c)) if elapsed is not None else None
    trigger = what.as_trigger() if isinstance(what, PlanTerm) else None
    if trigger is not None:
        return Suspend(event=trigger, timeout=seconds, on_timeout=on_timeout, reason="wait_event")
    # a logical condition, re-checked after every reasoning cycle
    agent = ctx.agent
    b = ctx.b
    from agentspeak.solver import solve_first
    if solve_first(agent, what, b):
        return done(ctx)
    return Suspend(until=lambda: solve_first(agent, what, b), timeout=seconds, on_timeout=on_timeout,
                   reason="wait_condition")


@internal_action(".stopMAS", args=(0, 2))
def stop_mas(ctx, delay=0, code=0):
    """Stop every agent of the MAS; with a delay (ms), each agent gets ``+jag_shutting_down(Delay)``
    and runs until then, the caller too (as Jason). ``.stopMAS(D, Code)``: the MAS's process exits with
    ``Code``, as Jason's JVM does (Jason's own test manager stops with code 1 when tests failed or were
    not launched; a run that dropped that code reported a partial count as success)."""
    exit_code = int(code) if isinstance(code, (int, float)) and not isinstance(code, bool) else 0
    ctx.agent.arch.stop_mas(ctx.agent, (delay or 0) / 1000.0, exit_code)
    return True if delay else Suspend(reason="stopping")


@internal_action(".include", args=(1, 2))
def include(ctx, path, namespace=None):
    """``.include(File[, NS])``: load an .asl file now (beliefs, rules, plans, goals), found beside the agent's
    source, then along the project's source path. With NS, into that name space (Jason's modules); an
    unbound NS gets a new name space ``ns<N>``."""
    import os
    from agentspeak.namespaces import unique_ns_id
    from agentspeak.sources import find_source
    from agentspeak.stdlib.registry import read_program
    if not isinstance(path, str):
        raise wrong_arguments(".include needs a file name")
    if namespace is not None and not isinstance(namespace, Var) and not (isinstance(namespace, Literal)
                                                                         and not namespace.args):
        raise wrong_arguments("the second argument of .include (the name space) must be an atom or a variable")
    agent = ctx.agent
    base = os.path.dirname(agent.source_file) if agent.source_file else "."
    source_dirs = getattr(getattr(agent.arch, "runtime", None), "source_dirs", ())
    full = find_source(path, base, tuple(source_dirs)) or (path if os.path.isabs(path) else os.path.join(base, path))
    ns = "default"
    if isinstance(namespace, Var):
        ns = f"ns{unique_ns_id()}"
        if not ctx.unify(namespace, Literal(ns)):
            return False
    elif namespace is not None:
        ns = namespace.functor
    try:
        with open(full, encoding="utf-8") as f:
            text = f.read()
    except OSError as exc:
        raise IAError("ia_failed", f".include: cannot read {path} ({exc.strerror or exc})") from None
    from agentspeak.errors import AslSyntaxError
    try:
        program = read_program(text, full, ns)
    except AslSyntaxError as exc:
        raise IAError("ia_failed", f".include: {exc}") from None
    agent.load(program)


