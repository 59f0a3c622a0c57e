"""Jason's arithmetic functions (``jason/functions/*.java``), one small function each.

They are used inside expressions anywhere (``X = math.max(A, B) + 1``, contexts, rules, arguments
of actions). Numbers follow Java's ``double`` arithmetic: ``math.sqrt(-1)`` is NaN and
``math.log(0)`` is -Infinity instead of Python exceptions, ``math.round`` is Java's ``Math.round``
(halves go up: ``math.round(-2.5)`` is -2). List functions use the numbers of the list and skip
other elements, as Jason does; ``math.max``/``math.min`` of a list start from Java's
``Double.MIN_VALUE``/``Double.MAX_VALUE``, so ``math.max([-3])`` is 4.9E-324 in Jason and here.

``rule_function`` builds a function from a rule, for the ``{ register_function("ns.f", N, "p") }``
directive: ``ns.f(A1..AN)`` is the last argument of the first solution of ``p(A1..AN, R)``.
"""
from __future__ import annotations

import math
import time

from agentspeak.stdlib.registry import FUNCTIONS, FunctionError, FunctionSpec, arith_function
from agentspeak.terms import Cons, Literal, NIL, Term, Var, is_list, list_items, resolve, to_str

_NAN = math.nan
_JAVA_DOUBLE_MIN = 5e-324      # Double.MIN_VALUE: the start of Jason's max over a list
_JAVA_DOUBLE_MAX = 1.7976931348623157e308
_LONG_MAX = 2 ** 63 - 1
_LONG_MIN = -(2 ** 63)


def _number(x: Term) -> int | float:
    if type(x) is int or type(x) is float:
        return x
    raise FunctionError(f"the argument '{to_str(x)}' is not a number")


def _numbers_of_list(x: Term) -> list:
    """The numeric elements of a list (Jason's list functions ignore the others)."""
    if not is_list(x):
        raise FunctionError(f"'{to_str(x)}' is not a list")
    return [t for t in _items(x) if type(t) is int or type(t) is float]


def _items(x: Term) -> list:
    try:
        return list_items(x)
    except TypeError:
        raise FunctionError(f"'{to_str(x)}' is not a proper list") from None


def _java_div(a: float, b: float) -> float:
    """``a / b`` on Java doubles: a zero divisor gives NaN or an infinity, not an exception."""
    if b == 0:
        return _NAN if a == 0 or math.isnan(a) else math.copysign(math.inf, a) * math.copysign(1.0, b)
    return a / b


# -- one argument, Java's Math ----------------------------------------------------------------
def _unary(name: str, fn, doc: str) -> None:
    def function(x):
        n = _number(x)
        try:
            return fn(n)
        except ValueError:  # outside the domain: Java answers NaN
            return _NAN
        except OverflowError:
            return math.inf
    function.__doc__ = doc
    arith_function(name, args=1)(function)


_unary("math.abs", abs, "Absolute value.")
_unary("math.sqrt", math.sqrt, "Square root (NaN below zero).")
_unary("math.sin", math.sin, "Sine of an angle in radians.")
_unary("math.cos", math.cos, "Cosine of an angle in radians.")
_unary("math.tan", math.tan, "Tangent of an angle in radians.")
_unary("math.asin", math.asin, "Arc sine, in [-pi/2, pi/2] (NaN outside [-1, 1]).")
_unary("math.acos", math.acos, "Arc cosine, in [0, pi] (NaN outside [-1, 1]).")
_unary("math.atan", math.atan, "Arc tangent, in [-pi/2, pi/2].")
_unary("math.floor", lambda n: n if math.isinf(n) or math.isnan(n) else math.floor(n),
       "The largest integer not greater than the argument.")
_unary("math.ceil", lambda n: n if math.isinf(n) or math.isnan(n) else math.ceil(n),
       "The smallest integer not less than the argument.")


@arith_function("math.log", args=1)
def log(x):
    """Natural logarithm (-Infinity at 0, NaN below)."""
    n = _number(x)
    if n == 0:
        return -math.inf
    if n < 0 or math.isnan(n):
        return _NAN
    return math.log(n)


@arith_function("math.round", args=1)
def round_(x):
    """Java's ``Math.round``: the closest integer, halves rounded up (-2.5 gives -2)."""
    n = _number(x)
    if type(n) is int:
        return n
    if math.isnan(n):
        return 0
    if math.isinf(n):
        return _LONG_MAX if n > 0 else _LONG_MIN
    low = math.floor(n)
    result = low + 1 if n - low >= 0.5 else low  # n - floor(n) is exact for doubles
    return max(_LONG_MIN, min(_LONG_MAX, result))


# -- constants, randomness, time -----------------------------------------------------------------
@arith_function("math.pi", args=0)
def pi():
    """The number pi."""
    return math.pi


@arith_function("math.e", args=0)
def e():
    """The number e."""
    return math.e


@arith_function("math.random", args=(0, 1), agent=True)
def random(agent, limit=None):
    """A random number in [0, 1), or in [0, N) with an argument (the agent's generator, which
    ``.set_random_seed`` seeds)."""
    from agentspeak.stdlib.system import _rng
    r = _rng(agent).random()
    if type(limit) is int or type(limit) is float:
        return r * limit
    return r


@arith_function("system.time", args=0)
def system_time():
    """Milliseconds since the epoch (Java's ``System.currentTimeMillis``)."""
    return time.time_ns() // 1_000_000


# -- two numbers or a list ---------------------------------------------------------------------
def _max_min(name: str, pick, start: float, doc: str) -> None:
    def function(first, second=None):
        if second is not None and type(first) in (int, float) and type(second) in (int, float):
            if math.isnan(first) or math.isnan(second):
                return _NAN
            return pick(first, second)
        if is_list(first):  # Jason looks at a list first argument whatever the second is
            best = start
            for n in _numbers_of_list(first):
                best = pick(best, n)  # a NaN element is skipped, as Java's `n > max`
            return best
        raise FunctionError("needs two numbers or a list")
    function.__doc__ = doc
    arith_function(name, args=(1, 2))(function)


_max_min("math.max", max, _JAVA_DOUBLE_MIN, "The larger of two numbers, or the largest number of a list.")
_max_min("math.min", min, _JAVA_DOUBLE_MAX, "The smaller of two numbers, or the smallest number of a list.")


@arith_function("math.sum", args=1)
def sum_(lst):
    """Sum of the numbers of a list (0 for an empty list)."""
    return _sum(_numbers_of_list(lst))


@arith_function("math.average", args=1)
def average(lst):
    """Mean of the numbers of a list (NaN for none, as Jason's 0/0)."""
    nums = _numbers_of_list(lst)
    return _java_div(_sum(nums), len(nums))


@arith_function("math.mean", args=1)
def mean(lst):
    """Mean of the numbers of a list (fails for none)."""
    nums = _numbers_of_list(lst)
    if not nums:
        raise FunctionError("no numbers to take the mean of")
    return _sum(nums) / len(nums)


@arith_function("math.median", args=1)
def median(lst):
    """Median of a list of numbers (fails for an empty list or a non-number element)."""
    if not is_list(lst):
        raise FunctionError(f"'{to_str(lst)}' is not a list")
    items = _items(lst)
    for t in items:
        if type(t) is not int and type(t) is not float:
            raise FunctionError(f"the list has a non-number, '{to_str(t)}'")
    if not items:
        raise FunctionError("no numbers to take the median of")
    items.sort()
    mid = len(items) // 2
    return items[mid] if len(items) % 2 else (items[mid - 1] + items[mid]) / 2


@arith_function("math.std_dev", args=1)
def std_dev(lst):
    """Sample standard deviation of the numbers of a list (divides by n - 1)."""
    nums = _numbers_of_list(lst)
    avg = _java_div(_sum(nums), len(nums))
    squares = _sum([(n - avg) * (n - avg) for n in nums])
    variance = _java_div(squares, len(nums) - 1)
    return _NAN if math.isnan(variance) or variance < 0 else math.sqrt(variance)


def _sum(nums: list) -> float:
    total = 0.0
    for n in nums:  # left to right, as Java's loop (fsum would round differently)
        total += n
    return total


# -- the agent and its terms -------------------------------------------------------------------
@arith_function(".count", args=1, unground=True, agent=True)
def count(agent, query):
    """Number of solutions of a query against the agent's beliefs and rules."""
    from agentspeak.solver import solve
    n = 0
    for _ in solve(agent, query, {}):
        n += 1
    return n


@arith_function(".length", args=1)
def length(x):
    """Length of a list or of a string."""
    if type(x) is str:
        return len(x)
    if x is NIL or type(x) is Cons:
        return len(_items(x))
    raise FunctionError(f"'{to_str(x)}' is not a list or a string")


def rule_function(name: str, arity: int, predicate: str) -> FunctionSpec:
    """A function answered by a rule (or belief, or internal action): ``name(A1..AN)`` is R in
    the first solution of ``predicate(A1..AN, R)`` (Jason's ``RuleToFunction``)."""
    def function(agent, *args):
        from agentspeak.solver import solve
        result = Var("Result")
        query = Literal(predicate, tuple(args) + (result,))
        b: dict = {}
        for _ in solve(agent, query, b):
            value = resolve(result, b)
            if type(value) is int or type(value) is float:
                return value
            raise FunctionError(f"the result of {to_str(resolve(query, b))} is not a number")
        raise FunctionError(f"no solution for {to_str(query)}")
    function.__doc__ = f"{name}/{arity} answered by {predicate}/{arity + 1}"
    function.remake = (rule_function, (name, arity, predicate))   # how FunctionSpec pickles it (not a closure)
    return FunctionSpec(name, function, (arity,), unground_ok=True, needs_agent=True, doc=function.__doc__)


def check_function_name(name: str) -> str | None:
    """Why ``name`` cannot be a user function (Jason's ``checkFunctionName``), or None."""
    if name in FUNCTIONS.functions:
        return f"cannot register the function {name} twice"
    if "." not in name:
        return f"the function {name} was not registered: a function name has a '.'"
    if name.startswith("."):
        return f"the function {name} was not registered: a user function name cannot start with '.'"
    return None
