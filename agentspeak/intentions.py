"""Events, intended means and intentions (Jason's Circumstance data), and the plan library.

An intended means (``IntendedMeans``) is one running instance of a plan: the plan (shared, never
copied), its own bindings dict, and a stack of frames (the plan body plus any ``if``/``while``/
``for`` block being executed). An intention is a stack of intended means.

``Event``, ``Frame``, ``IntendedMeans`` and ``Intention`` are also built without ``__init__`` on the
message path (see ``agentspeak.agent._new``): a new slot must be set there too, and declared in
``intentions.pxd`` (their C types in the compiled build).
"""
from __future__ import annotations

import itertools
from collections import deque
from typing import Iterator

from agentspeak.program import ACHIEVE, ADD, BEL, DEL, Plan, Trigger
from agentspeak.terms import Literal, NsTerm, Term, split_ns

_intention_ids = itertools.count(1)


class Event:
    """A trigger waiting to be handled. ``intention`` is None for external events.

    ``handles`` is set on ``-!g`` failure events: the intended means of the goal that failed.
    """

    __slots__ = ("trigger", "intention", "handles")

    def __init__(self, trigger: Trigger, intention: "Intention | None" = None, handles=None) -> None:
        self.trigger, self.intention, self.handles = trigger, intention, handles

    def __repr__(self) -> str:
        return f"Event({self.trigger})"


class Frame:
    """A body being executed: the plan body, or a block of ``if``/``while``/``for``."""

    __slots__ = ("body", "pc", "kind", "loop", "solutions", "index", "reset")

    def __init__(self, body: tuple, kind: str = "body", loop=None, solutions=None, reset=()) -> None:
        self.body = body
        self.pc = 0
        self.kind = kind            # "body" | "while" | "for"
        self.loop = loop            # the While/For instruction
        self.solutions = solutions  # for: the list of solution bindings
        self.index = 0
        self.reset = reset          # variables unbound again before each iteration


class IntendedMeans:
    __slots__ = ("plan", "b", "frames", "result", "handles", "event_literal", "trigger_b")

    def __init__(self, plan: Plan, b: dict, event_literal: Term) -> None:
        self.plan = plan
        self.b = b
        self.frames = [Frame(plan.body)]
        # what the caller unifies with (changed by TRO): the event's literal, as Jason's IntendedMeans
        # keeps the event's trigger; the plan's own trigger would drop annotations of arguments
        self.result = event_literal
        self.handles: IntendedMeans | None = None
        self.event_literal = event_literal
        # Jason(ER): the bindings when the plan was selected, where its sub-plans start from
        self.trigger_b = dict(b) if plan.sub_library is not None else None

    @property
    def trigger(self) -> Trigger:
        return self.plan.trigger

    def is_finished(self) -> bool:
        frames = self.frames
        return len(frames) == 1 and frames[0].pc >= len(frames[0].body)

    def current(self):
        """The body formula about to run (None between frames)."""
        f = self.frames[-1]
        return f.body[f.pc] if f.pc < len(f.body) else None

    def at_last_step(self) -> bool:
        """True when the step being executed is the last one of the plan (for tail calls)."""
        return len(self.frames) == 1 and self.frames[0].pc == len(self.frames[0].body) - 1

    def __repr__(self) -> str:
        return f"IM({self.plan.trigger} @ {self.plan.source_file}:{self.plan.line})"


class Intention:
    __slots__ = ("id", "stack", "suspended", "atomic", "waiting", "fork", "dropped", "branch", "__weakref__")

    def __init__(self, im: IntendedMeans | None = None) -> None:
        self.id = next(_intention_ids)
        self.stack: list[IntendedMeans] = [] if im is None else [im]  # its first intended means, if given
        self.suspended: str | None = None   # why it is not in the running queue (None = running)
        self.atomic = 0                     # number of [atomic] plans on the stack
        self.waiting = None                 # the Suspend (or event) it waits for
        self.fork = None                    # ForkGroup it belongs to, for |&| and |||
        self.dropped = False
        # Jason(ER): a branch runs a sub-plan for a belief update on behalf of another intention;
        # (that intention, the intended means whose sub-plan it runs)
        self.branch: tuple | None = None

    def __repr__(self) -> str:
        return f"intention {self.id}: " + " / ".join(repr(im) for im in reversed(self.stack))

    def goal_ims(self) -> Iterator[IntendedMeans]:
        return reversed(self.stack)


KQML_RECEIVED_KEY = (ADD, ACHIEVE, False, "kqml_received", 4)
"""The index key of ``+!kqml_received(Sender, Performative, Content, MsgId)`` plans."""


def _has_source(label: Literal, source: Term) -> bool:
    for a in label.annots or ():
        if type(a) is Literal and a.functor == "source" and len(a.args) == 1 and a.args[0] == source:
            return True
    # a plan from the agent's own source has no source annotation: it is the agent's (self)
    return type(source) is Literal and source.functor == "self" and not any(
        type(a) is Literal and a.functor == "source" for a in label.annots or ())


class PlanLibrary:
    """Plans in source order, indexed by trigger (op, kind, functor/arity); variable triggers last-bound."""

    def __init__(self) -> None:
        self.plans: list[Plan] = []
        self._index: dict[tuple, list[Plan]] | None = None
        self._var_plans: dict[tuple, list[Plan]] = {}
        self._ns_plans: dict[tuple, list[Plan]] = {}
        self._plan_order: dict[int, int] = {}
        self.kqml_override = False  # a plan is relevant to +!kqml_received/4 (valid while _index is)
        self.has_meta = False       # a ^!g plan exists: the agent posts goal-state meta events
        self.has_goal_conditions = False  # a `+!g <: C` plan exists: C is checked every cycle
        self.has_extras = False     # either of the two above: the end of a cycle checks them
        self.has_jag = False        # a +jag_sleeping/+jag_awaking plan exists: the agent posts them
        self.has_update_sub_plans = False  # a sub-plan reacts to +b/-b: such events may branch intentions
        self.has_sub_plans = False  # some plan has sub-plans (failure plans are looked for in them too)
        self.father: PlanLibrary | None = None  # a library of sub-plans: the library of their plan

    def add(self, plan: Plan, at_end: bool = True) -> None:
        plan.ensure_label()
        if plan.trigger.op == "^":
            self.has_meta = True
        if plan.goal_condition is not None:
            self.has_goal_conditions = True
            self.has_extras = True
        lit = plan.trigger.literal
        if getattr(lit, "functor", None) in ("jag_sleeping", "jag_awaking"):
            self.has_jag = True
            self.has_extras = True
        if plan.sub_plans:
            self._add_sub_library(plan)
        if at_end:
            self.plans.append(plan)
        else:
            self.plans.insert(0, plan)
        self._index = None

    def _add_sub_library(self, plan: Plan) -> None:
        """Jason(ER): the plan's sub-plans get a library of their own whose father is this one (an
        event of the plan's intention looks there first, then up the fathers); the flags that make
        the agent check goal conditions and branch on belief updates go up to the root library."""
        sub = PlanLibrary()
        sub.father = self
        plan.sub_library = sub
        for sp in plan.sub_plans:
            q = sp.copy()
            q.scope = sub
            sub.add(q)
        root = self
        while root is not None:
            root.has_sub_plans = True
            if sub.has_goal_conditions:
                root.has_goal_conditions = root.has_extras = True
            if sub.has_update_sub_plans or any(p.trigger.kind == BEL and p.trigger.op != "^" for p in sub.plans):
                root.has_update_sub_plans = True
            root = root.father

    def remove(self, label: Literal, source: Term = None) -> list[Plan]:
        """Remove the plans of this label (with a source: only those whose label says that source,
        Jason's ``.remove_plan(L, Source)``)."""
        removed = [p for p in self.plans if p.label is not None and p.label.functor == label.functor
                   and (source is None or _has_source(p.label, source))]
        if removed:
            self.plans = [p for p in self.plans if p not in removed]
            self._index = None
        return removed

    def by_label(self, name: str) -> Plan | None:
        for p in self.plans:
            if p.label is not None and p.label.functor == name:
                return p
        return None

    def _build(self) -> dict:
        index: dict[tuple, list[Plan]] = {}
        var_plans: dict[tuple, list[Plan]] = {}
        # `+N::b(X)`: by (op, kind, negated, name, arity), of any name space; `+!ns::G`: by (op, kind, ns)
        ns_plans: dict[tuple, list[Plan]] = {}
        for p in self.plans:
            key = p.trigger.key
            if key is None:
                lit = p.trigger.literal
                if type(lit) is NsTerm and type(lit.body) is Literal:
                    body = lit.body
                    ns_plans.setdefault((p.trigger.op, p.trigger.kind, body.neg, body.functor, len(body.args)),
                                        []).append(p)
                elif type(lit) is NsTerm and type(lit.ns) is Literal:  # `-!G[error(E)]` of a module in ns
                    ns_plans.setdefault((p.trigger.op, p.trigger.kind, lit.ns.functor), []).append(p)
                else:
                    var_plans.setdefault((p.trigger.op, p.trigger.kind), []).append(p)
            else:
                index.setdefault(key, []).append(p)
        self._var_plans = var_plans
        self._ns_plans = ns_plans
        if var_plans or ns_plans:  # merge variable-trigger plans into every list, keeping source order
            order = self._plan_order = {id(p): i for i, p in enumerate(self.plans)}
            for key, plans in index.items():
                extra = self._unkeyed(key)
                if extra:
                    plans.extend(extra)
                    plans.sort(key=lambda p: order[id(p)])
        self.kqml_override = bool(index.get(KQML_RECEIVED_KEY) or var_plans.get((ADD, ACHIEVE))
                                  or ns_plans.get(KQML_RECEIVED_KEY))
        self._index = index
        return index

    def _unkeyed(self, key: tuple) -> list:
        """The plans with a variable trigger or a variable name space that an event of ``key`` may match."""
        extra = list(self._var_plans.get((key[0], key[1]), ()))
        if self._ns_plans:
            ns, name = split_ns(key[3])
            extra += self._ns_plans.get((key[0], key[1], key[2], name, key[4]), ())
            extra += self._ns_plans.get((key[0], key[1], ns), ())
        return extra

    def relevant(self, trigger: Trigger) -> list[Plan]:
        index = self._index if self._index is not None else self._build()
        lit = trigger.literal
        key = (trigger.op, trigger.kind, lit.neg, lit.functor, len(lit.args)) if type(lit) is Literal else None
        if key is None:
            return [p for p in self.plans if p.trigger.op == trigger.op and p.trigger.kind == trigger.kind]
        found = index.get(key)
        if found is not None:
            return found
        if self._ns_plans:  # an event of a name space no plan names: the plans of any name space
            found = self._unkeyed(key)
            if len(found) > 1:
                order = self._plan_order
                found.sort(key=lambda p: order[id(p)])
            index[key] = found
            return found
        return self._var_plans.get((trigger.op, trigger.kind), [])

    def has_candidates(self, op: str, kind: str, lit: Term) -> bool:
        return bool(self.relevant(Trigger(op, kind, lit)))

    def __len__(self) -> int:
        return len(self.plans)

    def __iter__(self):
        return iter(self.plans)


class EventQueue(deque):
    """FIFO of events (Jason's default ``selectEvent``)."""


__all__ = ["Event", "Frame", "IntendedMeans", "Intention", "PlanLibrary", "EventQueue",
           "ADD", "DEL", "BEL", "ACHIEVE"]
