"""Printing: ``.print`` and ``.println`` (both one line in Jason 3), ``.printf``, ``.log``."""
from __future__ import annotations

import logging

from agentspeak.stdlib.registry import internal_action, wrong_arguments
from agentspeak.terms import to_print_str, to_str

log = logging.getLogger("faultmas.agentspeak")


@internal_action(".print")
def print_(ctx, *args) -> None:
    """Print the arguments, concatenated (strings without quotes), as one line ``[agent] text``."""
    ctx.agent.arch.print_line(ctx.agent, "".join(to_print_str(a) for a in args))


@internal_action(".println")
def println(ctx, *args) -> None:
    """Same as ``.print`` (Jason 3 logs a whole line either way)."""
    ctx.agent.arch.print_line(ctx.agent, "".join(to_print_str(a) for a in args))


@internal_action(".printf", args=(1, None))
def printf(ctx, fmt, *args) -> None:
    """Java-style format (``%s``, ``%d``, ``%f``... handled by Python's % operator)."""
    if not isinstance(fmt, str):
        raise wrong_arguments(".printf needs a format string")
    values = tuple(a if isinstance(a, (int, float, str)) else to_str(a) for a in args)
    try:
        text = fmt % values
    except (TypeError, ValueError) as exc:
        raise wrong_arguments(f".printf: {exc}") from None
    ctx.agent.arch.print_line(ctx.agent, text)


@internal_action(".log", args=(1, None))
def log_(ctx, level, *args) -> None:
    """``.log(severe|warning|info|fine|..., args...)``: as Jason's console shows it by default, ``info``
    and above are printed as a line of the agent (like ``.print``); finer levels go to the logger."""
    levels = {"severe": logging.ERROR, "warning": logging.WARNING, "info": logging.INFO, "config": logging.INFO,
              "fine": logging.DEBUG, "finer": logging.DEBUG, "finest": logging.DEBUG}
    name = getattr(level, "functor", str(level))
    text = "".join(to_print_str(a) for a in args)
    if levels.get(name, logging.INFO) >= logging.INFO and name != "config":
        ctx.agent.arch.print_line(ctx.agent, text)
    else:
        log.log(levels.get(name, logging.INFO), "[%s] %s", ctx.agent.name, text)
