"""One AgentSpeak agent and its reasoning cycle, following Jason's transition system.

Each ``cycle()`` is Jason's: **sense** (perceive and update beliefs, action feedback, timers, ONE
message), **deliberate** (select ONE event, find its relevant then applicable plans, first applicable
in source order, push the intended means), **act** (select ONE intention round-robin, execute ONE
body formula, then clear finished intended means). Method names follow the rules of the formal
semantics (``sel_ev``, ``appl_pl``, ``clr_int``; rule ExecInt is ``act``'s body, inlined because
it runs once per cycle). The body formulas ACT executes are ``agentspeak/body.py``; what an intention
that waits (``.wait``, an ask, a robot's action) goes through is ``agentspeak/suspension.py``.

The agent does no I/O of its own: perception, actions, messages and printing go through its
architecture (``agentspeak.arch.AgentArch``), so the same agent runs in-process, over Zenoh, or on a
robot bridge.
"""
from __future__ import annotations

import heapq
import itertools
import logging
import time
from collections import deque
from typing import Any, Callable, Iterator

from agentspeak import program as P
from agentspeak.beliefs import SOURCE_PERCEPT, SOURCE_SELF, BeliefBase, has_source
from agentspeak.body import _DISPATCH, IAContext, _new, bindings_free, fresh_goal  # noqa: F401  (_new: documented there, named here by others)
from agentspeak.communication import receive_message
from agentspeak.intentions import Event, Frame, IntendedMeans, Intention, PlanLibrary, _intention_ids
from agentspeak.program import ACHIEVE, ADD, BEL, DEL, META, Plan, Program, Trigger, plan_matcher
from agentspeak.solver import SolveError, _true_k, solve_first
from agentspeak.stdlib.registry import STDLIB, IAError, Registry, Suspend, yields_solutions
from agentspeak.suspension import check_conditions, notify_waiters, suspend_on
from agentspeak.terms import (
    NS_SEP, ArithmeticError_, Literal, NsTerm, Term, Var, resolve, to_str,
)
from agentspeak.unify import unify

log = logging.getLogger("faultmas.agentspeak")

_TRUE = Literal("true")
_JAG_SLEEPING = Literal("jag_sleeping")
_JAG_AWAKING = Literal("jag_awaking")
_seq = itertools.count()

TIMER_STEP = 0.001
"""How far a busy agent's timer clock moves in one reasoning cycle at most (seconds), see ``sense``."""
TIMER_MAX_LAG = 2.0
"""... and how far behind the real clock it may fall at most."""




class Agent:
    """An AgentSpeak agent: belief base, plan library, events, intentions and a mailbox."""

    # From source, the fields as slots (the compiled build: agent.pxd, the same names): CPython 3.11 keeps
    # at most 30 attribute names of a class's instances in its shared, inlined form; with more, every
    # agent's attributes live in a plain dict and the reasoning cycle's reads and writes of them get
    # slower (ring100 ran 7 % more instructions with 31). ``__dict__`` still takes what users, bridges
    # and internal actions add.
    __slots__ = ("name", "arch", "_arch_seen", "_perceive", "clock", "registry", "tro", "bb", "plans", "events",
                 "running", "suspended", "mailbox", "feedback", "timers", "timer_lag", "timer_seen",
                 "timer_busy", "event_waiters", "condition_waiters", "pending_futures", "pending_asks",
                 "atomic_intention", "percepts", "source_file", "stopped", "cycles", "failures_unhandled",
                 "dropped", "current_intention", "sleeping_evt", "__dict__")

    def __init__(self, name: str, program: Program | None = None, arch: Any = None,
                 registry: Registry = STDLIB, tro: bool = True, source_file: str = "") -> None:
        from agentspeak.arch import AgentArch  # local import: arch depends on agent's types only

        self.name = name
        self.arch = arch if arch is not None else AgentArch()
        self._see_arch(self.arch)
        self.registry = registry
        self.tro = tro
        self.bb = BeliefBase()
        self.plans = PlanLibrary()
        self.events: deque[Event] = deque()
        self.running: deque[Intention] = deque()
        self.suspended: dict[int, Intention] = {}
        self.mailbox: deque = deque()          # appended from any thread
        self.feedback: deque = deque()         # callables run in the sense phase (thread-safe append)
        self.timers: list = []                 # heap of (when, seq, callback)
        self.timer_lag = 0.0                   # how far the timer clock is behind the real one (see sense)
        self.timer_seen = 0.0                  # real time of the last look at the timers
        self.timer_busy = False                # busy at that look
        self.timer_lost = 0.0                  # all lag ever counted (never reset): see communication._answer
        self.event_waiters: list = []          # (trigger pattern, intention, suspend)
        self.condition_waiters: list = []      # (intention, suspend)
        self.pending_futures = 0               # actions / awaited results in flight
        self.pending_asks: dict[str, Any] = {}
        self.atomic_intention: Intention | None = None
        self.percepts: set[Literal] = set()
        self.source_file = source_file
        self.stopped = False
        self.cycles = 0
        self.failures_unhandled = 0
        self.dropped: dict[str, int] = {}
        self.current_intention: Intention | None = None  # the intention of the event or formula at hand
        self.sleeping_evt = False  # +jag_sleeping was posted and nothing woke the agent since
        if program is not None:
            self.load(program)

    def _see_arch(self, arch: Any) -> None:
        """A new architecture (set at start, or by a bridge): the default ``perceive`` never returns
        percepts, so the sense phase skips calling it. Its environment's clock becomes the agent's
        (``AgentArch.environment_clock``); timers already set keep the time they had left."""
        from agentspeak.arch import AgentArch
        self._arch_seen = arch
        self._perceive = None if type(arch).perceive is AgentArch.perceive else arch.perceive
        clock = getattr(arch, "environment_clock", None)
        clock = (clock() if clock is not None else None) or time.monotonic
        old = getattr(self, "clock", None)
        if old is not None and old is not clock and self.timers:
            now, then = old(), clock()
            self.timers = [(then + (when + self.timer_lag - now), seq, callback) for when, seq, callback in self.timers]
            self.timer_lag = 0.0   # deadlines now on the new clock itself
            heapq.heapify(self.timers)
        self.clock = clock
        """Seconds, the agent's time: its timers (``.wait``, ``.at``, answer and action timeouts) count in
        it. Wall time (``time.monotonic``), as in Jason, unless the environment has a clock of its own (a
        simulated robot's: see ``robot_bridge.clock``)."""

    # ------------------------------------------------------------------ loading
    def load(self, program: Program) -> None:
        """Add a program's beliefs (posting +b events), rules, plans and initial goals."""
        for plan in program.plans:
            self.plans.add(plan)
        for rule in program.rules:
            self.bb.add_rule(rule)
        for warning in program.warnings:
            log.warning(warning)
        for lit in program.beliefs:
            self.add_initial_belief(lit)
        for goal in program.goals:
            self.add_initial_goal(goal)

    def add_initial_belief(self, lit: Literal) -> None:
        if not has_source(lit):
            lit = lit.add_annot(SOURCE_SELF)
        added = self.bb.add(lit, at_end=True)
        if added is not None:
            self.post_external(Trigger(ADD, BEL, added))

    def add_initial_goal(self, goal: Literal) -> None:
        goal = fresh_goal(goal, {})
        self.post_external(Trigger(ADD, ACHIEVE, goal), force=True)

    # ------------------------------------------------------------------ knowledge base (for the solver)
    def candidates(self, lit: Literal, b: dict) -> list:
        return self.bb.candidates(lit, b)

    def rules_for(self, lit: Literal) -> list:
        return self.bb.rules_for(lit)

    def call_internal(self, lit: Literal, b: dict, trail: list) -> Iterator[None]:
        """An internal action used inside a formula (context, rule, test): a solution generator."""
        spec = self.registry.get(lit.functor)
        if spec is None:
            raise SolveError("ia_failed", f"unknown internal action {lit.functor}")
        args = tuple(resolve(a, b) for a in lit.args)
        self._check_arity(spec, lit, args)
        ctx = IAContext(self, None, None, b, trail)
        try:
            result = spec.function(ctx, *args)
        except IAError as exc:
            raise SolveError(exc.error, exc.message) from None
        if yields_solutions(result):
            return result
        if isinstance(result, Suspend):
            raise SolveError("ia_failed", f"{lit.functor} cannot be used in a formula (it suspends)")
        return iter((None,)) if result is None or result is True else iter(())

    @staticmethod
    def _check_arity(spec, lit: Literal, args: tuple) -> None:
        n = len(args)
        if n < spec.min_args or (spec.max_args is not None and n > spec.max_args):
            want = (f"{spec.min_args}" if spec.max_args == spec.min_args
                    else f"{spec.min_args} to {spec.max_args if spec.max_args is not None else 'any'}")
            raise IAError("wrong_arguments", f"{lit.functor} takes {want} arguments, got {n}")

    # ------------------------------------------------------------------ events
    def post_external(self, trigger: Trigger, force: bool = False) -> None:
        """An event that starts a new intention (percepts, messages, ``!!g``, initial goals)."""
        notify_waiters(self, trigger)
        if self.plans.has_meta and trigger.kind == ACHIEVE and trigger.op == ADD:
            self.goal_state(trigger, "pending")
        if force or self.plans.relevant(trigger) or self.plans.has_update_sub_plans:
            self.events.append(Event(trigger))  # (a sub-plan of an intention may be relevant)
        elif trigger.kind != BEL:
            self.events.append(Event(trigger))  # a goal without plan still fails visibly

    def post_internal(self, trigger: Trigger, intention: Intention) -> None:
        """An event on ``intention``, which waits until the event is handled."""
        if self.event_waiters:
            notify_waiters(self, trigger)
        self.events.append(Event(trigger, intention))
        intention.suspended = "event"

    # ------------------------------------------------------------------ the reasoning cycle
    def cycle(self) -> bool:
        """One reasoning cycle. Returns True if anything happened."""
        self.cycles += 1
        if self.arch is not self._arch_seen:
            self._see_arch(self.arch)
        if self.sleeping_evt:
            self._awaking()
        if self._perceive is not None or self.feedback or self.timers:
            did = self.sense()
        elif self.mailbox:  # sense() with only a message to read, inlined
            receive_message(self, self.mailbox.popleft())
            did = True
        else:
            did = False
        if self.events and self.deliberate():
            did = True
        if self.running:
            self.act()
            did = True
        if self.condition_waiters:
            check_conditions(self)
        if self.plans.has_extras:
            self._end_of_cycle()
        return did

    def _end_of_cycle(self) -> None:
        """Goal conditions that now hold; Jason's +jag_sleeping when nothing is left to do (once, until
        something wakes the agent). Only for agents with such plans."""
        if self.plans.has_goal_conditions:
            self._check_goal_conditions()
        if self.plans.has_jag and not self.sleeping_evt and not (
                self.events or self.running or self.mailbox or self.feedback):
            self.sleeping_evt = True
            self.post_external(Trigger(ADD, BEL, _JAG_SLEEPING))

    # ------------------------------------------------------------------ deadlines and goal conditions
    def _check_deadline(self, goal: Literal, intention: Intention) -> None:
        """``!g[hard_deadline(MS)]``: if g is still pursued MS milliseconds later, it fails with
        ``error(deadline_reached)`` (Jason's TransitionSystem.checkHardDeadline)."""
        for a in goal.annots:
            if type(a) is Literal and a.functor == "hard_deadline" and len(a.args) == 1 \
                    and type(a.args[0]) in (int, float):
                size = len(intention.stack)
                self.add_timer(a.args[0] / 1000.0, lambda: self._deadline(goal, intention, size))
                return

    def _deadline(self, goal: Literal, intention: Intention, size: int) -> None:
        if intention.dropped or len(intention.stack) < size:
            return
        im = intention.stack[size - 1] if size else None
        if im is None or im.event_literal is not goal:
            return
        del intention.stack[size:]
        im.frames[:] = [im.frames[0]]
        intention.waiting = None  # a wait in progress is abandoned
        self.running_remove(intention)
        intention.suspended = None
        self.suspended.pop(intention.id, None)
        self._fail(intention, "deadline_reached", f"hard deadline of {to_str(goal)} reached")
        if intention.suspended is None and not intention.dropped:
            self._requeue(intention)

    def running_remove(self, intention: Intention) -> None:
        try:
            self.running.remove(intention)
        except ValueError:
            pass

    def _check_goal_conditions(self) -> None:
        """Jason 3.2's ``+!g <: C``: a goal whose condition holds is achieved at once (applyClrSatInt)."""
        for intention in self.intentions():
            stack = intention.stack
            for idx, im in enumerate(stack):
                gc = im.plan.goal_condition
                if gc is None:
                    continue
                if solve_first(self, gc, dict(im.b)):
                    del stack[idx + 1:]
                    im.frames[:] = [im.frames[0]]
                    im.frames[0].pc = len(im.frames[0].body) + 1  # achieved (not only its body done)
                    intention.waiting = None
                    intention.suspended = None
                    self.suspended.pop(intention.id, None)
                    self.event_waiters = [w for w in self.event_waiters if w[1] is not intention]
                    self.condition_waiters = [w for w in self.condition_waiters if w[0] is not intention]
                    self.running_remove(intention)
                    self.clr_int(intention)
                    if not intention.dropped and intention.stack:
                        self.running.append(intention)
                    break

    def _awaking(self) -> None:
        """Something other than the +jag_sleeping plan woke the agent: +jag_awaking (Jason's rule)."""
        awake = bool(self.mailbox)
        if not awake:
            for ev in self.events:
                lit = ev.trigger.literal
                if not (type(lit) is Literal and lit.functor == "jag_sleeping"):
                    awake = True
                    break
        if not awake:
            for i in self.running:
                if not any(type(im.event_literal) is Literal and im.event_literal.functor == "jag_sleeping"
                           for im in i.stack):
                    awake = True
                    break
        if awake:
            self.sleeping_evt = False
            self.post_external(Trigger(ADD, BEL, _JAG_AWAKING))

    def has_work(self) -> bool:
        return bool(self.events or self.running or self.mailbox or self.feedback)

    def is_idle(self) -> bool:
        """Nothing to do now and nothing that will happen by itself (timers, results in flight)."""
        return not (self.has_work() or self.timers or self.pending_futures)

    def next_timer(self) -> float | None:
        """When the next timer is due at the earliest, on the agent's clock (``self.clock``)."""
        return self.timers[0][0] + self.timer_lag if self.timers else None

    # -- sense
    def sense(self) -> bool:
        did = False
        timers = self.timers
        if timers and not (self.running or self.events) and self.clock == time.monotonic:
            # an idle agent comes to a due timer late (the process ran other agents or got no CPU): on a
            # thread of its own it would have gone on at the deadline, so that wait is lag too. The
            # timer itself ends now; the agent's later ones keep their order after it (a .wait due 10 ms
            # after an .at ends after the .at's plan ran, as in Jason). Measured before this cycle does
            # anything (a timer it sets now is due by the clock it sees now). Wall time only: an
            # environment's clock is polled (CLOCK_POLL_S), lateness there is no lost CPU.
            late = self.clock() - self.timer_lag - timers[0][0]
            if late > 0.0:
                self._count_lag(late)
        perceive = self._perceive
        if perceive is not None:
            percepts = perceive(self)
            if percepts is not None:
                self.buf(percepts)
                did = True
        while self.feedback:
            self.feedback.popleft()()
            did = True
        timers = self.timers
        if timers:
            # Timers run by the agent's timer clock, in the order of their deadlines on it. While the agent
            # stays busy (events or intentions to run) that clock moves at most TIMER_STEP per cycle, and
            # deadlines are set on it: when the process gets the CPU seldom, what an agent on a thread of
            # its own does in a few cycles after one deadline still happens before the next (.wait(50)
            # then 20 formulas, before another intention's .wait(150) ends; six .wait(50) in a row end
            # before a .wait(500) begun with them), as Jason on a machine with time to spare. The clock
            # falls at most TIMER_MAX_LAG behind, and no timer ends before its time on the real clock.
            now = self.clock()   # the agent's time: its environment's clock, if it has one
            busy = bool(self.running or self.events)
            if busy and self.timer_busy:
                slow = now - self.timer_seen - TIMER_STEP
                if slow > 0.0:
                    self._count_lag(slow)
            self.timer_seen = now
            self.timer_busy = busy
            clock = now - self.timer_lag
            if timers[0][0] <= clock:
                due = []
                while timers and timers[0][0] <= clock:
                    due.append(heapq.heappop(timers)[2])
                for callback in due:  # a callback may set a timer due at once: it runs next cycle
                    callback()
                # busy from now on if a timer gave it work (a wait ended): until its next cycle it is
                # an agent with work that gets no CPU, whose lost time is lag as well
                self.timer_busy = bool(self.running or self.events or self.feedback)
                did = True
        if self.mailbox:
            receive_message(self, self.mailbox.popleft())
            did = True
        return did

    def _count_lag(self, lost: float) -> None:
        """The agent lost ``lost`` seconds (see sense): its timer clock falls behind by as much (at most
        TIMER_MAX_LAG), and ``timer_lost`` keeps the total, so what the agent answers later is stamped by
        the time it would have answered on a thread of its own (agentspeak.communication._answer)."""
        old = self.timer_lag
        lag = old + lost
        self.timer_lag = lag if lag < TIMER_MAX_LAG else TIMER_MAX_LAG
        self.timer_lost += self.timer_lag - old

    def buf(self, percepts) -> None:
        """Belief update function: add new percepts, remove those no longer perceived."""
        current = set()
        for p in percepts:
            plain = p.without_annots() if p.annots else p
            current.add(plain)
        for gone in self.percepts - current:
            removed = self.bb.remove(Literal(gone.functor, gone.args, (SOURCE_PERCEPT,), gone.neg))
            if removed is not None:
                self.post_external(Trigger(DEL, BEL, removed))
        for new in current - self.percepts:
            added = self.bb.add(Literal(new.functor, new.args, (SOURCE_PERCEPT,), new.neg))
            if added is not None:
                self.post_external(Trigger(ADD, BEL, added))
        self.percepts = current

    # -- deliberate
    def sel_ev(self) -> Event | None:
        events = self.events
        atomic = self.atomic_intention
        if atomic is not None and not atomic.dropped:
            for i, ev in enumerate(events):
                if ev.intention is atomic:
                    del events[i]
                    return ev
            return None
        return events.popleft()

    def deliberate(self) -> bool:
        if self.atomic_intention is None:
            ev = self.events.popleft()
        else:
            ev = self.sel_ev()
            if ev is None:
                return False
        trigger = ev.trigger
        intention = ev.intention
        if intention is not None and intention.dropped:
            return True
        self.current_intention = intention  # what .intention(..., current) means in a plan context
        if self.bb.select_option:
            return self._select_option_bb(ev)
        plans = self.plans
        if plans.has_sub_plans:  # Jason(ER): only agents with sub-plans pay for these checks
            if intention is not None:
                if intention.stack:
                    top_plan = intention.stack[-1].plan
                    if top_plan.sub_library is not None or top_plan.scope is not None:
                        return self._deliberate_in_scope(ev)
            elif plans.has_update_sub_plans and trigger.kind == BEL and trigger.op != META:
                self._branch_for_update(trigger)
        lit = trigger.literal
        if type(lit) is Literal:
            # PlanLibrary.relevant, inlined; every plan listed under the key has the event's
            # functor and arity, or a variable trigger (whose matcher has no variables tuple)
            args = lit.args
            index = plans._index if plans._index is not None else plans._build()
            relevant = index.get((trigger.op, trigger.kind, lit.neg, lit.functor, len(args)))
            if relevant is None:
                relevant = plans.relevant(trigger)
            for a in args:  # (a loop: `Var in map(type, args)` costs 3x more for one argument)
                ta = type(a)
                if ta is Var or (ta is Literal and NS_SEP in a.functor) or ta is NsTerm:
                    # variables in the event: bind by unification (shared or repeated ones); so too a value
                    # whose name space a trigger's variable must match (agentspeak.unify.in_other_ns)
                    args = None
                    break
        else:
            args = None
            relevant = plans.relevant(trigger)
        if not relevant:
            self._no_plan(ev, "no_relevant", f"found a goal for which there is no relevant plan: {trigger}")
            return True
        trail: list = []  # one for every context: a context that fails undoes its own bindings
        b = None          # the bindings of the plan tried before, if its context failed cleanly
        for plan in relevant:
            tvars, context, _ = plan.matcher or plan_matcher(plan)
            if tvars is not None and args is not None:
                # distinct variables <- the event's arguments (a display: dict(zip()) costs 5x more)
                n = len(args)
                if n == 1:
                    if b is None:
                        b = {tvars[0]: args[0]}
                    else:  # reused: a dict costs more than emptying one
                        b.clear()
                        b[tvars[0]] = args[0]
                elif n == 2:
                    b = {tvars[0]: args[0], tvars[1]: args[1]}
                else:
                    b = dict(zip(tvars, args))
            else:
                b = {}
                if not unify(plan.trigger.literal, lit, b, []):
                    continue
            if context is not None:
                try:
                    if not context(self, b, trail, _true_k):
                        continue
                except (SolveError, ArithmeticError_, RecursionError, TypeError, ValueError, AttributeError) as exc:
                    trail = []
                    b = None
                    log.warning("[%s] error in the context of the plan at %s:%s: %s", self.name,
                                plan.source_file, plan.line, getattr(exc, "message", exc))
                    continue
            if intention is None and not plan.atomic:
                # push_im's new intention, Intention(IntendedMeans(plan, b, lit)), without class calls
                f = Frame.__new__(Frame)
                f.body, f.pc, f.kind, f.loop, f.solutions, f.index, f.reset = plan.body, 0, "body", None, None, 0, ()
                im = IntendedMeans.__new__(IntendedMeans)
                im.plan, im.b, im.frames, im.result, im.handles, im.event_literal = plan, b, [f], lit, None, lit
                im.trigger_b = None if plan.sub_library is None else dict(b)
                new = Intention.__new__(Intention)
                new.id, new.stack, new.suspended, new.atomic = next(_intention_ids), [im], None, 0
                new.waiting, new.fork, new.dropped, new.branch = None, None, False, None
                self.running.append(new)
            else:
                self.push_im(ev, plan, b)
            if trigger.op == ADD and trigger.kind == ACHIEVE:
                if plans.has_meta:
                    self.goal_state(trigger, "executing")
                if type(lit) is Literal and lit.annots is not None and len(lit.annots) > 1:
                    self._check_deadline(lit, intention if intention is not None else self.running[-1])
            return True
        self._no_plan(ev, "no_applicable", f"found a goal for which there is no applicable plan: {trigger}")
        return True

    def _select_option_bb(self, ev: Event) -> bool:
        """Jason 3.3's ``select__option(Event, IntentionId, Plan, Unifier)`` rules: every option (each
        applicable plan with each solution of its context) is tested with the rule, and the first that
        passes is taken (Agent.selectOptionBB; -1 is the id of an external event's intention)."""
        from agentspeak.solver import solve
        from agentspeak.terms import make_list
        trigger, intention = ev.trigger, ev.intention
        lit = trigger.literal
        options: list = []
        for plan in self.plans.relevant(trigger):
            b: dict = {}
            if not unify(plan.trigger.literal, lit, b, []):
                continue
            if plan.context is None:
                options.append((plan, b))
                continue
            try:
                for _ in solve(self, plan.context, b, []):
                    options.append((plan, dict(b)))
            except (SolveError, ArithmeticError_, RecursionError, TypeError, ValueError) as exc:
                log.warning("[%s] error in the context of the plan at %s:%s: %s", self.name,
                            plan.source_file, plan.line, getattr(exc, "message", exc))
        event = P.PlanTerm(plan=Plan(Trigger(trigger.op, trigger.kind, lit)), bare=True)
        ident = intention.id if intention is not None else -1
        chosen = None
        for plan, b in options:
            unifier = make_list([Literal("map", (Var(v.name), resolve(v, b))) for v in b
                                 if type(v) is Var and not v.name.startswith("_")])
            query = Literal("select__option", (event, ident, P.PlanTerm(plan=plan.resolved(b)), unifier))
            try:
                ok = solve_first(self, query, {})
            except (SolveError, ArithmeticError_, RecursionError, TypeError, ValueError) as exc:
                log.warning("[%s] error in select__option: %s", self.name, getattr(exc, "message", exc))
                ok = False
            if ok and chosen is None:
                chosen = (plan, b)
        if chosen is None:
            kind = "applicable" if self.plans.relevant(trigger) else "relevant"
            self._no_plan(ev, "no_" + kind, f"found a goal for which there is no {kind} plan: {trigger}")
            return True
        self.push_im(ev, *chosen)
        if trigger.op == ADD and trigger.kind == ACHIEVE and self.plans.has_meta:
            self.goal_state(trigger, "executing")
        return True

    # ------------------------------------------------------------------ Jason(ER) sub-plans
    def _deliberate_in_scope(self, ev: Event) -> bool:
        """An event of an intention whose top plan has sub-plans, or is one: its plans are looked for
        in the top plan's sub-plans (or the library it lives in), then up the fathers to the agent's
        library; the first applicable plan is taken (Jason's applyRelApplPlRule1 with scopes)."""
        trigger, intention = ev.trigger, ev.intention
        top_plan = intention.stack[-1].plan
        library = top_plan.sub_library if top_plan.sub_library is not None else top_plan.scope
        error = "no_relevant"
        while library is not None:
            for plan in library.relevant(trigger):
                error = "no_applicable"
                b = self._option(plan, trigger.literal, self._scope_bindings(intention, plan))
                if b is not None:
                    self.push_im(ev, plan, b)
                    if trigger.op == ADD and trigger.kind == ACHIEVE and self.plans.has_meta:
                        self.goal_state(trigger, "executing")
                    return True
            library = library.father
        kind = "relevant" if error == "no_relevant" else "applicable"
        self._no_plan(ev, error, f"found a goal for which there is no {kind} plan: {trigger}")
        return True

    @staticmethod
    def _relevant_in_scope(trigger: Trigger, intention: Intention) -> bool:
        """A plan for ``trigger`` among the sub-plans the intention's top plan sees (its own, then the
        blocks around it): where a failure plan ``-!g`` of a sub-goal may be written."""
        top = intention.stack[-1].plan if intention.stack else None
        library = None if top is None else (top.sub_library if top.sub_library is not None else top.scope)
        while library is not None:
            if library.relevant(trigger):
                return True
            library = library.father
        return False

    def _option(self, plan: Plan, lit: Term, start: dict | None) -> dict | None:
        """The bindings with which ``plan`` is applicable to the event literal ``lit`` (None if it is not)."""
        b = dict(start) if start else {}
        if not unify(plan.trigger.literal, lit, b, []):
            return None
        context = (plan.matcher or plan_matcher(plan))[1]
        if context is None:
            return b
        try:
            return b if context(self, b, [], _true_k) else None
        except (SolveError, ArithmeticError_, RecursionError, TypeError, ValueError, AttributeError) as exc:
            log.warning("[%s] error in the context of the plan at %s:%s: %s", self.name,
                        plan.source_file, plan.line, getattr(exc, "message", exc))
            return None

    @staticmethod
    def _scope_bindings(intention: Intention, plan: Plan) -> dict | None:
        """A sub-plan starts from the bindings its plan's intended means had when it was selected."""
        if plan.scope is None:
            return None
        for owner in (intention, intention.branch[0] if intention.branch else None):
            for im in reversed(owner.stack if owner is not None else ()):
                if im.plan.sub_library is plan.scope:
                    return im.trigger_b
        return None

    def _branch_for_update(self, trigger: Trigger) -> None:
        """Jason(ER): an external +b/-b for which a sub-plan of an intended means is applicable runs that
        sub-plan on a branch of its intention (the intention itself stays where it is), with the
        intended means' current bindings; the nearest such intended means of each intention."""
        for intention in self.intentions():
            if intention.branch is not None:
                continue
            for im in reversed(intention.stack):
                library = im.plan.sub_library
                if library is None:
                    continue
                b = None
                for plan in library.relevant(trigger):
                    b = self._option(plan, trigger.literal, im.b)
                    if b is not None:
                        branch = Intention(IntendedMeans(plan, b, trigger.literal))
                        branch.branch = (intention, im)
                        self.running.append(branch)
                        break
                if b is not None:
                    break

    def _no_plan(self, ev: Event, error: str, message: str) -> None:
        trigger = ev.trigger
        intention = ev.intention
        if trigger.kind == BEL or trigger.op != ADD:
            if intention is not None:  # internal +b/-b event with no plan: the intention just goes on
                if trigger.kind == BEL:
                    self._requeue(intention)
                else:
                    log.warning("[%s] no applicable failure-handling plan for %s; dropping %r",
                                self.name, trigger, intention)
                    self.drop_intention(intention)
            return
        if intention is None and type(trigger.literal) is Literal and trigger.literal.functor == "kqml_received" \
                and len(trigger.literal.args) == 4:
            held = getattr(self, "kqml_messages", None)
            msg = held.pop(trigger.literal.args[3], None) if held else None
            if msg is not None:  # no user plan applies: the default semantics (Jason's kqmlPlans.asl)
                from agentspeak.communication import receive_by_default
                receive_by_default(self, msg)
                return
        if intention is None:
            # an external goal (.at, !!g, a message) without a plan: Jason posts -!g when a plan is
            # relevant for it (generateGoalDeletionFromEvent), else it warns
            failed = Trigger(DEL, trigger.kind, trigger.literal)
            if type(trigger.literal) is Literal and self.plans.relevant(failed):
                annots = self._failure_annots(error, message)
                self.events.append(Event(Trigger(DEL, trigger.kind, _add_annots(trigger.literal, annots))))
                return
            log.warning("[%s] %s", self.name, message)
            self.failures_unhandled += 1
            return
        # an internal subgoal without a plan: fail it (its -!g plan, or the callers')
        lit = trigger.literal
        annots = self._failure_annots(error, message, self._current_instr(intention))
        failed = Trigger(DEL, trigger.kind, lit)
        if self.plans.relevant(failed) or (self.plans.has_sub_plans and self._relevant_in_scope(failed, intention)):
            self.post_internal(Trigger(DEL, trigger.kind, _add_annots(lit, annots)), intention)
            return
        self._fail(intention, error, message, annots=annots)

    def push_im(self, ev: Event, plan: Plan, b: dict) -> None:
        """Rule AddIM (with tail-recursion optimisation)."""
        trigger = ev.trigger
        intention = ev.intention
        if intention is None:
            intention = Intention(IntendedMeans(plan, b, trigger.literal))
            if plan.atomic:
                intention.atomic += 1
                self.atomic_intention = intention
            self.running.append(intention)  # a new intention: not in any queue yet
            return
        stack = intention.stack
        if ev.handles is not None or (trigger.op == DEL and trigger.kind != BEL):
            im = IntendedMeans(plan, b, trigger.literal)
            im.handles = ev.handles if ev.handles is not None else _PENDING_GOAL
            stack.append(im)
        else:
            tail = (plan.matcher or plan_matcher(plan))[2] if stack and self.tro else None
            top = stack[-1] if tail is not None and trigger.op == ADD and trigger.kind == ACHIEVE else None
            frames = top.frames if top is not None else None
            if (frames is not None and len(frames) == 1 and top.handles is None
                    and frames[0].pc == len(frames[0].body) - 1
                    and (top.plan.matcher or plan_matcher(top.plan))[2] == tail):
                # Tail call: a +!g event for a plan of the caller's own +!g trigger (same functor and
                # arity, neither atomic), the caller at its last formula. The finished caller is
                # replaced by the callee, which reports its result directly to the caller's caller,
                # so the stack stays flat. The caller's intended means object is reused for the
                # callee (nothing else refers to a finished caller).
                if self.plans.has_meta:
                    self._goal_achieved(top)
                if len(stack) == 1:
                    top.result = plan.trigger.literal
                elif not bindings_free(top.result):  # the usual chain keeps the first call's literal
                    top.result = resolve(top.result, top.b)
                top.plan = plan
                top.b = b
                top.event_literal = trigger.literal
                top.trigger_b = None if plan.sub_library is None else dict(b)
                f0 = frames[0]
                f0.body = plan.body
                f0.pc = 0
            else:
                stack.append(IntendedMeans(plan, b, trigger.literal))
        if plan.atomic:
            intention.atomic += 1
            self.atomic_intention = intention
        if not intention.dropped:  # _requeue, inlined
            intention.suspended = None
            if self.suspended:
                self.suspended.pop(intention.id, None)
            if intention not in self.running:
                self.running.append(intention)

    # -- act
    def sel_int(self) -> Intention:
        atomic = self.atomic_intention
        if atomic is not None:
            if atomic.dropped or atomic.atomic == 0:
                self.atomic_intention = None
            elif atomic.suspended is None:
                try:
                    self.running.remove(atomic)
                except ValueError:
                    pass
                return atomic
            else:
                return None
        return self.running.popleft()

    def act(self) -> None:
        intention = self.running.popleft() if self.atomic_intention is None else self.sel_int()
        if intention is None or intention.dropped or not intention.stack:
            return
        intention.suspended = None
        self.current_intention = intention
        # rule ExecInt (this runs once per reasoning cycle)
        im = intention.stack[-1]
        frame = im.frames[-1]
        if frame.pc >= len(frame.body):
            if frame.kind != "body":
                self._loop_step(intention, im, frame)
            self.clr_int(intention)
        else:
            instr = frame.body[frame.pc]
            try:
                _DISPATCH[type(instr)](self, intention, im, frame, instr)
            except IAError as exc:
                self._fail(intention, exc.error, exc.message, instr, extra=exc.annots)
            except SolveError as exc:
                self._fail(intention, exc.error, exc.message, instr)
            except ArithmeticError_ as exc:
                self._fail(intention, "wrong_arguments", str(exc), instr)
            except RecursionError:
                self._fail(intention, "wrong_arguments", "a term too deep or cyclic to work with", instr)
            except Exception as exc:  # a broken internal action fails its intention, never the agent
                log.exception("[%s] %s raised", self.name, instr)
                self._fail(intention, "ia_failed", f"{instr}: {type(exc).__name__}: {exc}", instr)
            else:
                if intention.suspended is None and not intention.dropped:
                    # clr_int's two usual cases inlined: the top plan still has formulas to run
                    # (the intention stays in the queue), or the intention's only plan is done
                    stack = intention.stack
                    if stack:
                        top = stack[-1]
                        frames = top.frames
                        if len(frames) == 1:
                            f0 = frames[0]
                            if f0.pc < len(f0.body):
                                self.running.append(intention)
                                return
                            if len(stack) == 1 and top.handles is None and top.plan.goal_condition is None:
                                stack.pop()
                                if top.plan.atomic:
                                    intention.atomic -= 1
                                if self.plans.has_meta:
                                    self._goal_achieved(top)
                                self._finished(intention)
                                return
                    self.clr_int(intention)
        if intention.suspended is None and intention.stack and not intention.dropped:
            self.running.append(intention)

    def _requeue(self, intention: Intention) -> None:
        if intention.dropped:
            return
        intention.suspended = None
        self.suspended.pop(intention.id, None)
        if intention not in self.running:
            self.running.append(intention)

    def _suspend(self, intention: Intention, reason: str) -> None:
        intention.suspended = reason
        self.suspended[intention.id] = intention

    # ------------------------------------------------------------------ clearing finished plans
    def clr_int(self, intention: Intention) -> None:
        """Rule ClrInt: pop finished intended means, and let the caller go on after its ``!g``."""
        stack = intention.stack
        if stack:  # the usual case, at once: the top plan still has formulas to run
            frames = stack[-1].frames
            if len(frames) == 1 and frames[0].pc < len(frames[0].body):
                return
        while stack:
            im = stack[-1]
            frames = im.frames
            while len(frames) > 1 and frames[-1].pc >= len(frames[-1].body) and frames[-1].kind == "body":
                frames.pop()
            if len(frames) != 1 or frames[0].pc < len(frames[0].body):  # not im.is_finished()
                return
            if im.plan.goal_condition is not None and frames[0].pc == len(frames[0].body):
                # Jason(ER): a body done is not a goal achieved; the intention waits until the goal
                # condition holds, or .done/.succeed_goal finishes it (those set pc past the end)
                self.running_remove(intention)
                self._suspend(intention, "wait_goal_condition")
                return
            stack.pop()
            if im.plan.atomic:
                intention.atomic -= 1
            if self.plans.has_meta:
                self._goal_achieved(im)
            if im.handles is not None:
                # a failure-handling plan finished: drop everything down to the goal that failed
                if im.handles is not _PENDING_GOAL:
                    while stack:
                        gone = stack.pop()
                        if gone.plan.atomic:
                            intention.atomic -= 1
                        if gone is im.handles:
                            break
                if stack:
                    self._advance(stack[-1])
                continue
            if not stack:
                break
            if im.plan.trigger.kind == BEL:
                # a plan reacting to the caller's +b/-b: the caller had already moved past that formula
                continue
            caller = stack[-1]
            instr = caller.current()
            value = resolve(im.result, im.b)
            if instr is not None and type(instr) in (P.Achieve, P.Test):
                trail: list = []
                if type(instr.term) is Literal or type(instr.term) is Var:
                    unify(instr.term, value, caller.b, trail)
            self._advance(caller)
        # the intention is finished
        self._finished(intention)

    # ------------------------------------------------------------------ goal states (meta events)
    def goal_state(self, trigger: Trigger, state: str, reason: Term = "") -> None:
        """Post ``^!g[state(S)[reason(R)]]`` at the start of the next cycle, when a plan is relevant
        (Jason's GoalListenerForMetaEvents: pending, executing, suspended, waiting, resumed, achieved,
        failed, finished, dropped). Only called when the plan library has a ``^`` plan."""
        lit = trigger.literal
        if type(lit) is not Literal:
            return
        annot = Literal("state", (Literal(state),), (Literal("reason", (reason,)),))
        meta = Trigger(META, trigger.kind, lit.add_annot(annot))
        if not self.plans.relevant(meta):
            return
        self.feedback.append(lambda: self.events.appendleft(Event(meta)))
        self.arch.wake(self)

    def _goal_achieved(self, im: IntendedMeans) -> None:
        trig = im.plan.trigger
        if trig.kind != BEL and trig.op != META:
            t = Trigger(trig.op, trig.kind, resolve(im.event_literal, im.b))
            self.goal_state(t, "achieved")
            self.goal_state(t, "finished")

    def _finished(self, intention: Intention) -> None:
        intention.dropped = True
        if self.atomic_intention is intention:
            self.atomic_intention = None
        if self.suspended:
            self.suspended.pop(intention.id, None)
        if intention.fork is not None:
            intention.fork.branch_done(self, intention, True)

    @staticmethod
    def _advance(im: IntendedMeans) -> None:
        im.frames[-1].pc += 1

    # -- loops
    def _loop_step(self, intention: Intention, im: IntendedMeans, frame: Frame) -> None:
        """The end of a while/for block: decide (one step, as Jason's .loop/.foreach) whether to go on."""
        b = im.b
        for v in frame.reset:
            b.pop(v, None)
        if frame.kind == "while":
            if solve_first(self, frame.loop.cond, b):
                frame.pc = 0
                return
        else:  # for
            if frame.index < len(frame.solutions):
                b.update(frame.solutions[frame.index])
                frame.index += 1
                frame.pc = 0
                return
        im.frames.pop()

    # ------------------------------------------------------------------ failure
    def _failure_annots(self, error: str, message: str, instr=None, extra: tuple = ()) -> tuple:
        annots = [Literal("error", (Literal(error),)), Literal("error_msg", (message,))]
        if instr is not None:
            code = instr.term if hasattr(instr, "term") else Literal(str(instr))
            annots.append(Literal("code", (code if isinstance(code, (Literal, Var)) else str(instr),)))
            annots.append(Literal("code_src", (source_url(self.source_file),)))
            annots.append(Literal("code_line", (getattr(instr, "line", 0),)))
        annots.extend(extra)
        return tuple(annots)

    def _current_instr(self, intention: Intention):
        return intention.stack[-1].current() if intention.stack else None

    def _fail(self, intention: Intention, error: str, message: str, instr=None, annots: tuple | None = None,
              extra: tuple = ()) -> None:
        """Plan failure: post ``-!g`` for the nearest goal below that has a failure plan (Jason 2.5
        cascade), or drop the intention with a warning naming the plan and line."""
        if annots is None:
            annots = self._failure_annots(error, message, instr or self._current_instr(intention), extra)
        stack = intention.stack
        skip_to = None
        for i in range(len(stack) - 1, -1, -1):
            im = stack[i]
            if skip_to is not None:
                if im is skip_to:
                    skip_to = None
                continue
            if im.handles is not None:
                skip_to = im.handles if im.handles is not _PENDING_GOAL else None
                if skip_to is None:
                    # the handler's goal has no intended means: the caller below has failed
                    continue
                continue
            trig = im.plan.trigger
            if trig.op == ADD and trig.kind != BEL:
                lit = resolve(trig.literal, im.b)
                if self.plans.has_meta:
                    self.goal_state(Trigger(ADD, trig.kind, resolve(im.event_literal, im.b)), "failed",
                                    Literal(error))
                failed = Trigger(DEL, trig.kind, lit)
                if type(lit) is Literal and (self.plans.relevant(failed) or (
                        self.plans.has_sub_plans and self._relevant_in_scope(failed, intention))):
                    self.events.append(Event(Trigger(DEL, trig.kind, _add_annots(lit, annots)), intention, im))
                    notify_waiters(self, self.events[-1].trigger)
                    self._suspend(intention, "event")
                    return
        top = stack[-1] if stack else None
        where = f" (plan {top.plan.trigger} at {top.plan.source_file}:{top.plan.line})" if top else ""
        line = getattr(instr, "line", None)
        at = f", line {line}" if line else ""
        self.failures_unhandled += 1
        log.warning("[%s] no failure event was generated for %s%s: %s (%s%s)", self.name,
                    top.plan.trigger if top else "?", where, message, error, at)
        self.drop_intention(intention)

    def drop_intention(self, intention: Intention) -> None:
        intention.dropped = True
        waiting = intention.waiting
        on_drop = getattr(getattr(waiting, "inner", waiting), "on_drop", None)   # (.suspend holds the inner wait)
        if on_drop is not None:
            on_drop()
        intention.stack.clear()
        try:
            self.running.remove(intention)
        except ValueError:
            pass
        self.suspended.pop(intention.id, None)
        if self.atomic_intention is intention:
            self.atomic_intention = None
        self.event_waiters = [w for w in self.event_waiters if w[1] is not intention]
        self.condition_waiters = [w for w in self.condition_waiters if w[0] is not intention]
        if intention.fork is not None:
            intention.fork.branch_done(self, intention, False)

    # ------------------------------------------------------------------ waiting (agentspeak.suspension)
    def suspend_on(self, intention: Intention, im: IntendedMeans, susp: Suspend, instr) -> None:
        """Suspend ``intention`` until ``susp`` says it may go on (then the formula succeeds or fails)."""
        suspend_on(self, intention, im, susp, instr)

    def _notify_waiters(self, trigger: Trigger) -> None:
        notify_waiters(self, trigger)

    # ------------------------------------------------------------------ timers, feedback, mail (any thread)
    def add_timer(self, seconds: float, callback: Callable[[], None]) -> None:
        now = self.clock()   # the agent's time: its environment's clock, if it has one
        if not self.timers:  # (set in a cycle of this agent: the time to its next cycle is busy if it is then)
            self.timer_lag, self.timer_seen, self.timer_busy = 0.0, now, True
        # on the timer clock: ``timers[0][0] + timer_lag`` is the real time it is due at the earliest
        heapq.heappush(self.timers, (now - self.timer_lag + max(0.0, seconds), next(_seq), callback))
        self.arch.wake(self)

    def hold_timers(self, seconds: float) -> None:
        """The agent was held (a debugger's pause) for ``seconds``: its timers' time stood still, so a
        wait begun before the hold has as long left after it, and the hold is no lateness (the timer
        clock's lag rules above then see nothing late; a timer set just after still runs this cycle).
        Wall time only: an environment's clock (a simulated robot's) went on without the agent."""
        if self.timers and seconds > 0.0 and self.clock is time.monotonic:
            self.timer_lag += seconds
            self.timer_seen += seconds

    def post_feedback(self, callback: Callable[[], None]) -> None:
        """Run ``callback`` in this agent's next sense phase (safe to call from any thread)."""
        self.feedback.append(callback)
        self.arch.wake(self)

    def deliver(self, message: Any, wake: bool = True) -> None:
        """Put a message in the mailbox (safe to call from any thread). A transport handing over a
        batch passes ``wake=False`` for each message and calls ``wake()`` once after the batch."""
        self.mailbox.append(message)
        if wake:
            self.arch.wake(self)

    def wake(self) -> None:
        """Tell the architecture this agent has work (after ``deliver(..., wake=False)``)."""
        self.arch.wake(self)

    # ------------------------------------------------------------------ trust and bookkeeping
    def accepts_plans_from(self, sender: str) -> bool:
        """May ``sender`` give us plans (tellHow)? Asked of the architecture (the MAS knows)."""
        policy = getattr(self.arch, "accepts_plans_from", None)
        return True if policy is None else bool(policy(self, sender))

    def count_dropped(self, reason: str) -> None:
        self.dropped[reason] = self.dropped.get(reason, 0) + 1

    def intentions(self) -> list[Intention]:
        seen: dict[int, Intention] = {}
        for i in list(self.running) + list(self.suspended.values()):
            if not i.dropped:
                seen[i.id] = i
        for ev in self.events:
            if ev.intention is not None and not ev.intention.dropped:
                seen[ev.intention.id] = ev.intention
        if self.atomic_intention is not None and not self.atomic_intention.dropped:
            seen[self.atomic_intention.id] = self.atomic_intention
        return sorted(seen.values(), key=lambda i: i.id)


def source_url(path: str) -> str:
    """A source file as Jason names it in ``code_src`` (``file:./x.asl``); names such as
    ``<string>`` stay as they are."""
    if not path or path.startswith("<") or ":" in path.split("/")[0]:
        return path or ""
    return "file:" + path


class _PendingGoal:
    """Marks a failure plan whose failed goal never got an intended means (no plan for it)."""

    def __repr__(self) -> str:
        return "<pending goal>"


_PENDING_GOAL = _PendingGoal()


def _add_annots(lit: Literal, annots: tuple) -> Literal:
    for a in annots:
        lit = lit.add_annot(a)
    return lit



__all__ = ["Agent", "IAContext"]
