"""Static checks of a parsed program against what the interpreter knows: internal actions by name and arity.

``faultmas asl check`` runs them after parsing, so an unknown ``.diagnos(...)`` or a ``.wait`` with four
arguments is reported at the desk (file:line and what is known instead) rather than failing on the robot.
The registry is the interpreter's own (``agentspeak.stdlib.registry.STDLIB``) with the plug-ins of the
``faultmas.internal_actions`` entry-point group loaded, so what passes here is what an agent can run.
"""
from __future__ import annotations

import difflib
from typing import Iterator

from agentspeak.program import Fork, For, If, Program, While
from agentspeak.stdlib.registry import STDLIB, Registry
from agentspeak.terms import And, Arith, Literal, Not, Or, Rel


def _literals(term) -> Iterator[Literal]:
    """Every literal in a formula or term, arguments included (``.findall(X, .member(X, L), R)``)."""
    stack = [term]
    while stack:
        t = stack.pop()
        if isinstance(t, Literal):
            yield t
            stack.extend(t.args)
        elif isinstance(t, (And, Or, Rel, Arith)):
            stack.extend((t.left, t.right))
        elif isinstance(t, Not):
            stack.append(t.arg)
        elif isinstance(t, (list, tuple)):
            stack.extend(t)


def _body_terms(body: tuple) -> Iterator[tuple[object, int]]:
    """(term, line) of every instruction of a plan body, nested bodies included."""
    for instr in body or ():
        line = getattr(instr, "line", 0)
        if isinstance(instr, If):
            for cond, branch in instr.branches:
                yield cond, line
                yield from _body_terms(branch)
            yield from _body_terms(instr.else_body or ())
        elif isinstance(instr, (While, For)):
            yield instr.cond, line
            yield from _body_terms(instr.body)
        elif isinstance(instr, Fork):
            for branch in instr.branches:
                yield from _body_terms(branch)
        else:
            for term in instr.terms():
                yield term, line


def internal_action_problems(program: Program, registry: Registry = STDLIB) -> list[str]:
    """``file:line: ...`` for every internal action the registry does not know, or calls with an arity it
    does not accept. Plug-ins are loaded first, as an agent would on its first unknown name."""
    if not registry._extensions_loaded:
        registry.load_extensions()
    places: list[tuple[object, int]] = []
    plans = list(program.plans)
    for plan in plans:
        plans.extend(plan.sub_plans)  # Jason(ER) sub-plans are checked too
        if plan.context is not None:
            places.append((plan.context, plan.line))
        places.extend((term, line or plan.line) for term, line in _body_terms(plan.body))
    places.extend((rule.body, rule.line) for rule in program.rules)
    problems = []
    for term, line in places:
        for literal in _literals(term):
            name = literal.functor
            if not isinstance(name, str) or not name.startswith("."):
                continue
            spec = registry.get(name)
            where = f"{program.source_file}:{line}"
            if spec is None:
                close = difflib.get_close_matches(name, registry.names(), n=1)
                hint = f"; did you mean {close[0]}?" if close else ""
                problems.append(f"{where}: unknown internal action {name}/{len(literal.args)}{hint}")
            elif len(literal.args) < spec.min_args or (spec.max_args is not None and len(literal.args) > spec.max_args):
                takes = (f"{spec.min_args}" if spec.min_args == spec.max_args else
                         f"{spec.min_args} or more" if spec.max_args is None else f"{spec.min_args} to {spec.max_args}")
                problems.append(f"{where}: {name} takes {takes} arguments, not {len(literal.args)}")
    return problems
