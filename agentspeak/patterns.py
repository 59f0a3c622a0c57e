"""Jason's goal-pattern directives: ``{ begin dg(g) } plans { end }`` and the like.

Each pattern rewrites the plans between ``begin`` and ``end`` and adds plans of its own, as Jason 3.3.2's
``jason.asSyntax.patterns.goal`` classes do (Bordini, Hübner & Wooldridge, *Programming Multi-Agent
Systems in AgentSpeak using Jason*, ch. 8): declarative goals (``dg``, ``bdg``, ``ebdg``), commitment
strategies (``bc``, ``smc``, ``rc``, ``omc``), maintenance goals (``mg``) and sequenced goal adoption
(``sga``). A pattern is a program transformation: after it, the agent runs ordinary plans.

The parser hands in ``parse`` (source text -> Program) so this module does not import the parser.
"""
from __future__ import annotations

from typing import Callable

from agentspeak.program import ACHIEVE, ADD, AddBel, Program, Test
from agentspeak.terms import And, Literal, Not, to_str
from agentspeak.unify import unifies

PATTERNS = ("dg", "bdg", "ebdg", "bc", "smc", "rc", "omc", "mg", "sga")


class PatternError(ValueError):
    """A pattern directive with arguments it cannot use (the parser reports it at the directive)."""


def apply_pattern(directive: Literal, inner: Program, parse: Callable[[str], Program], line: int = 0) -> Program:
    """The program the directive makes of ``inner`` (the clauses between its begin and end); the plans
    it adds say they come from the directive's ``line``."""
    name, args = directive.functor, directive.args
    arities = {"dg": (1,), "bdg": (1,), "ebdg": (1,), "bc": (1, 2), "smc": (2,), "rc": (2,),
               "omc": (3,), "mg": (1, 2), "sga": (3,)}
    if len(args) not in arities[name]:
        raise PatternError(f"the pattern {name} takes {' or '.join(map(str, arities[name]))} "
                           f"argument(s), not {len(args)}: {to_str(directive)}")
    if name != "sga" and not isinstance(args[0], Literal):
        raise PatternError(f"the goal of {name} must be a literal, not {to_str(args[0])}")
    out = _Builder(inner, parse, line)
    _PATTERN_FUNCS[name](out, *args)
    return out.program


class _Builder:
    def __init__(self, inner: Program, parse: Callable[[str], Program], line: int) -> None:
        self.line = line
        # the block's beliefs, rules and goals stay (Jason's patterns keep only plans: a user who writes
        # a belief there means it)
        self.program = Program(source_file=inner.source_file, beliefs=list(inner.beliefs),
                               rules=list(inner.rules), goals=list(inner.goals), warnings=list(inner.warnings))
        self.inner_plans = list(inner.plans)
        self.parse = parse

    def plan(self, text: str) -> None:
        for p in self.parse(text).plans:
            p.source_file, p.line = self.program.source_file, self.line
            self.program.plans.append(p)

    def inner(self) -> None:
        """The inner plans go here, in their order (once)."""
        self.program.plans.extend(self.inner_plans)
        self.inner_plans = []


def _goal_plans(out: _Builder, goal: Literal):
    """The inner ``+!g`` plans whose goal unifies with the pattern's."""
    for p in out.inner_plans:
        t = p.trigger
        if t.op == ADD and t.kind == ACHIEVE and unifies(t.literal, goal, {}):
            yield p


def _dg(out: _Builder, goal: Literal) -> None:
    g = to_str(goal)
    out.plan(f"+!{g} : {g}.")
    out.plan(f"+!{g} : .intend({g}).")
    for p in _goal_plans(out, goal):  # the goal is achieved only if it is believed afterwards
        p.body = p.body + (Test(p.trigger.literal, p.line),)
        p.matcher = None
    out.inner()
    out.plan(f"+{g} <- .succeed_goal({g}).")


def _bdg(out: _Builder, goal: Literal) -> None:
    _dg(out, goal)
    g = to_str(goal)
    out.plan(f"-!{g} <- !{g}.")


def _ebdg(out: _Builder, goal: Literal) -> None:
    g = to_str(goal)
    out.plan(f"+!{g} : {g}.")
    for i, p in enumerate(_goal_plans(out, goal), start=1):  # each plan is tried once per goal
        tried = Literal("p__f", (i, goal))
        p.context = Not(tried) if p.context is None else And(Not(tried), p.context)
        p.body = (AddBel(tried, p.line),) + p.body + (Test(p.trigger.literal, p.line),)
        p.matcher = None
    out.inner()
    out.plan(f"-!{g} <- !{g}.")
    out.plan(f"+{g} <- .abolish(p__f(_,{g})); .succeed_goal({g}).")
    out.plan(f"-{g} <- .abolish(p__f(_,{g})).")


def _sub_pattern(out: _Builder, goal: Literal, sub, default: str) -> None:
    sub = sub if sub is not None else Literal(default, (goal,))
    if not isinstance(sub, Literal) or sub.functor not in _PATTERN_FUNCS:
        raise PatternError(f"expected a pattern ({', '.join(PATTERNS)}) as the second argument, "
                           f"not {to_str(sub)}")
    _PATTERN_FUNCS[sub.functor](out, *sub.args)


def _bc(out: _Builder, goal: Literal, sub=None) -> None:
    _sub_pattern(out, goal, sub, "bdg")
    g = to_str(goal)
    out.plan(f"+!{g} <- !{g}.")


def _smc(out: _Builder, goal: Literal, failure) -> None:
    _bc(out, goal)
    out.plan(f"+{to_str(failure)} <- .fail_goal({to_str(goal)}).")


def _rc(out: _Builder, goal: Literal, motivation) -> None:
    _bc(out, goal)
    out.plan(f"-{to_str(motivation)} <- .succeed_goal({to_str(goal)}).")


def _omc(out: _Builder, goal: Literal, failure, motivation) -> None:
    _bc(out, goal)
    g, f = to_str(goal), to_str(failure)
    # the goal fails in the goal that called it, if any; a bottom goal is dropped
    out.plan(f"+{f} : .intend({g}, intention(_, [_, im(_, {{+!G}}, _, _) | _])) <- .fail_goal(G).")
    out.plan(f"+{f} <- .drop_intention({g}).")
    out.plan(f"-{to_str(motivation)} <- .succeed_goal({g}).")


def _mg(out: _Builder, goal: Literal, sub=None) -> None:
    _sub_pattern(out, goal, sub, "bc")
    out.program.beliefs.append(goal)
    g = to_str(goal)
    out.plan(f"-{g} <- !{g}.")


def _sga(out: _Builder, trigger, context, goal) -> None:
    if not isinstance(trigger, str) or not isinstance(context, str):
        raise PatternError('sga takes a trigger and a context as strings: sga("+e", "c", g)')
    g = to_str(goal)
    out.inner()
    out.plan(f"{trigger} : not f__l(_) & {context} <- !f__g({g}).")
    out.plan(f"{trigger} : f__l(_) & ({context}) <- +f__l({g}).")
    out.plan(f"+!f__g({g}) <- +f__l({g}); !{g}; -f__l({g}).")
    out.plan(f"-!f__g({g}) <- -f__l({g}).")
    out.plan(f"-f__l({g}) : f__l({g}) <- !f__g({g}).")


_PATTERN_FUNCS = {"dg": _dg, "bdg": _bdg, "ebdg": _ebdg, "bc": _bc, "smc": _smc, "rc": _rc,
                  "omc": _omc, "mg": _mg, "sga": _sga}
