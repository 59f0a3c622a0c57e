"""Run agents in one process: a scheduler that visits only agents with work, timers, idle detection.

The scheduler never polls idle agents (a ready queue, filled when an agent gets a message, an
event or a result), so a 100-agent ring costs what a 10-agent ring does. Results from other
threads (robot actions, Zenoh messages, the diagnoser) wake the loop through a condition variable;
a message or wake-up from the loop's own thread (an agent sending to another in-process) takes no
lock and notifies nobody: nobody sleeps while the loop runs.
"""
from __future__ import annotations

import logging
import threading
import time
from collections import deque
from functools import partial
from threading import get_ident
from typing import Callable, Iterable, Protocol

from agentspeak.agent import Agent
from agentspeak.arch import AgentArch
from agentspeak.communication import Message
from agentspeak.directory import DF_SENDER, Directory
from agentspeak.parse_cache import cached_program   # not the parser: a file parsed before skips Lark
from agentspeak.stdlib.registry import CURRENT
from agentspeak.terms import Literal

log = logging.getLogger("faultmas.agentspeak")

CYCLES_PER_TURN = 64
"""Reasoning cycles an agent runs before the next ready agent gets its turn (fairness)."""
TURN_SECONDS = 0.005
"""... or fewer, when its cycles are slow: with many busy agents a round stays short."""
URGENT_IN_ROW = 3
"""Agents that a message with a deadline (an ask with a timeout, an answer) puts first, in a row, before an
agent woken earlier gets its turn (see LocalRuntime._route_from)."""
CLOCK_POLL_S = 0.02
"""How often an idle loop looks at timers that count in an environment's clock (one simulator step)."""


def _when(entry: tuple) -> float:
    return entry[0]


class LocalArch(AgentArch):
    """Architecture of an agent run by ``LocalRuntime``: in-process mailbox, shared console."""

    def __init__(self, runtime: "LocalRuntime", **kwargs) -> None:
        super().__init__(**kwargs)
        self.runtime = runtime
        if type(self).send is LocalArch.send:  # one call per message instead of two (unless overridden)
            self.send = runtime._route_from  # type: ignore[method-assign]

    def send(self, agent: Agent, message: Message) -> bool:
        return self.runtime.route(message)

    def all_names(self, agent: Agent) -> list[str]:
        return self.runtime.names()

    def stop_mas(self, agent: Agent, delay: float = 0.0, exit_code: int = 0) -> None:
        self.runtime.stop(delay, exit_code)

    def wake(self, agent: Agent) -> None:
        self.runtime.wake(agent)

    def print_line(self, agent: Agent, text: str) -> None:
        self.runtime.print_line(agent.name, text)

    def accepts_plans_from(self, agent: Agent, sender: str) -> bool:
        return self.runtime.accepts_plans_from(sender)

    def create_agent(self, agent: Agent, name: str, source: str) -> str:
        return self.runtime.create_agent(name, source, creator=agent.name)

    def kill_agent(self, agent: Agent, name: str, delay: float = 0.0) -> bool:
        return self.runtime.kill_agent(name, delay)

    def clone_agent(self, agent: Agent, name: str) -> str:
        return self.runtime.clone_agent(agent, name)

    def directory(self, agent: Agent) -> Directory:
        """The directory facilitator of the MAS (``.df_*``): the runtime's (see ``LocalRuntime.directory``)."""
        return self.runtime.get_directory()

    def act(self, agent: Agent, action: Literal):
        env = self.runtime.environment
        return env(agent, action) if env is not None else None


def _shutting_down(agent: Agent, delay: float) -> None:
    """``+jag_shutting_down(MS)``: the agent is stopped or killed ``delay`` seconds from now (Jason's event)."""
    from agentspeak.program import ADD, BEL, Trigger

    agent.post_external(Trigger(ADD, BEL, Literal("jag_shutting_down", (round(delay * 1000),))), force=True)


class Membership(Protocol):
    """What a runtime whose MAS extends beyond this process (``agents.zenoh_arch``) is told of agents that come
    and go at run time (``.create_agent``, ``.clone``, ``.kill_agent``), so that they come and go everywhere."""

    def taken(self, name: str) -> bool:
        """Is ``name`` an agent of the MAS elsewhere (a new agent gets another name, as in Jason)?"""

    def admit(self, name: str) -> None:
        """Raise ``IAError`` (the creating formula fails, saying why) if no agent may be created as ``name``."""

    def joined(self, agent: Agent, creator: str) -> None:
        """``agent``, made by ``creator`` of this process, is now an agent of this runtime."""

    def left(self, name: str) -> None:
        """Agent ``name`` of this runtime was killed."""


class LocalRuntime:
    """All agents of a MAS in this process. Not thread-safe except ``wake``/``route``/``stop``."""

    def __init__(self, printer: Callable[[str, str], None] | None = None,
                 environment: Callable[[Agent, Literal], object] | None = None) -> None:
        self.agents: dict[str, Agent] = {}
        # Two queues, so that an agent that waited (for a message, a timer, its start) answers within a
        # turn or two, as an agent on a thread of its own does (Jason), while agents that stay busy turn
        # after turn share what is left: `ready` holds agents woken up, `busy` those whose turn ended
        # with work left. With 50 busy agents a round of every agent takes seconds on a loaded machine;
        # Jason's own tests expect a tell answered, or an .at run, within 200-500 ms.
        self.ready: deque[Agent] = deque()
        self.busy: deque[Agent] = deque()
        self._timed: set[Agent] = set()      # agents that had timers at the end of their last turn
        self._ready_set: set[str] = set()
        self._cond = threading.Condition()
        self._sleepers = 0                   # threads waiting on _cond (changed under its lock)
        self._stop_at: float | None = None
        self._loop_thread: int | None = None   # ident of the thread inside run(), if any
        self.stopped = False
        self.exit_code = 0                   # what .stopMAS(_, Code) asked the MAS's process to exit with
        self.printer = printer
        self.environment = environment
        self.trusted_senders: set[str] | None = None
        self.remote: Callable[[Message], bool] | None = None   # a transport for agents elsewhere
        self.undeliverable = 0
        self.source_dirs: list[str] = []     # where .create_agent and includes look (a project's aslSourcePath)
        self._yield_turn = False             # end the running agent's turn now (it created an agent)
        self._yield_to: Agent | None = None  # ... and run this one next, then the creator again
        self.directory: Directory | None = None  # the DF (.df_*), made on first use; a bridge to other
                                                 # processes puts its own back-end here (agents.directory)
        self._urgent_in_row = 0              # agents put first by a message with a deadline, in a row
        self._urgent: set[str] = set()       # ... their names, until their turn
        self.membership: Membership | None = None  # the MAS beyond this process, told of agents made and killed

    # -- set-up
    def add_agent(self, name: str, source: str | None = None, source_file: str = "<string>",
                  extra_beliefs: Iterable[Literal] = (), extra_goals: Iterable[Literal] = (),
                  arch: AgentArch | None = None, program=None) -> Agent:
        if name in self.agents:
            raise ValueError(f"an agent named {name!r} already exists")
        if program is None:
            program = cached_program(source or "", source_file)
        agent = Agent(name, arch=arch or LocalArch(self), source_file=source_file)
        for lit in extra_beliefs:
            agent.add_initial_belief(lit)
        agent.load(program)
        for goal in extra_goals:
            agent.add_initial_goal(goal)
        self.agents[name] = agent
        self.wake(agent)
        return agent

    def names(self) -> list[str]:
        return list(self.agents)

    def get_directory(self) -> Directory:
        """The directory facilitator of the agents of this runtime (made on first use)."""
        if self.directory is None:
            self.directory = Directory(self.tell_provider)
        return self.directory

    def tell_provider(self, subscriber: str, provider: str, service: str) -> None:
        """The DF's ``tell provider(Provider, "Service")`` to ``subscriber`` (any thread)."""
        self.route(Message(DF_SENDER, subscriber, "tell", Literal("provider", (Literal(provider), service))))

    def create_agent(self, name: str, source: str, creator: str | None = None) -> str:
        """A new agent from an ``.asl`` file, at run time (Jason's ``.create_agent``): the file is looked
        up as given, then along ``source_dirs``; a name in use (here or, with a ``membership``, anywhere in
        the MAS) gets a number appended, as in Jason. Raises ``IAError`` (the calling formula fails) for a
        missing file, a syntax error or a name the MAS refuses (``Membership.admit``)."""
        from agentspeak.errors import AslSyntaxError
        from agentspeak.sources import find_source
        from agentspeak.stdlib.registry import IAError
        path = find_source(source, None, self.source_dirs)
        if path is None:
            raise IAError("ia_failed", f".create_agent: cannot find {source!r} (looked in ., "
                                       f"{', '.join(self.source_dirs)})")
        unique = self._new_name(name)
        try:
            with open(path, encoding="utf-8") as f:
                text = f.read()
            program = cached_program(text, path, tuple(self.source_dirs))
        except OSError as exc:
            raise IAError("ia_failed", f".create_agent: cannot read {path}: {exc.strerror or exc}") from None
        except AslSyntaxError as exc:
            log.warning("%s", exc)
            raise IAError("ia_failed", f".create_agent({unique}): {exc}") from None
        if self.trusted_senders is not None:
            self.trusted_senders.add(unique)
        self._joined(self.add_agent(unique, source_file=path, program=program), creator)
        # the creator's turn ends after this cycle, so the new agent starts before the creator goes on
        # (Jason starts it on a thread of its own at once; a creator that loops must not starve it)
        self._yield_turn = True
        self._yield_to = self.agents[unique]
        return unique

    def clone_agent(self, original: Agent, name: str) -> str:
        """A new agent with a copy of ``original``'s beliefs, rules and plans (Jason's ``.clone``): no
        events, goals or intentions, so it waits for messages. A name in use gets a number appended."""
        import copy
        unique = self._new_name(name)
        clone = Agent(unique, arch=LocalArch(self), source_file=original.source_file)
        for plan in original.plans.plans:
            clone.plans.add(copy.copy(plan))  # a plan is not changed once in a library: a shallow copy
        for rule in original.bb.rules():
            clone.bb.add_rule(rule)
        for lit in original.bb.literals():
            clone.bb.add(lit, at_end=True)  # as they are, in order; no +b events (Jason clones the BB)
        if self.trusted_senders is not None:
            self.trusted_senders.add(unique)
        self.agents[unique] = clone
        self.wake(clone)
        self._joined(clone, original.name)
        return unique

    def _new_name(self, name: str) -> str:
        """``name``, or ``name_1``, ``name_2``... if it is taken (Jason's ``getNewAgentName``), admitted by the
        ``membership`` (``IAError`` otherwise)."""
        unique, n = name, 0
        while unique in self.agents or (self.membership is not None and self.membership.taken(unique)):
            n += 1
            unique = f"{name}_{n}"
        if self.membership is not None:
            self.membership.admit(unique)
        return unique

    def _joined(self, agent: Agent, creator: str | None) -> None:
        if self.membership is not None:
            self.membership.joined(agent, creator or agent.name)

    def _run_first(self, agent: Agent) -> None:
        """Put ``agent`` at the head of the ready queue (moved there if it is already queued)."""
        if agent.name in self._ready_set:
            for queue in (self.ready, self.busy):
                try:
                    queue.remove(agent)
                    break
                except ValueError:
                    pass
        self._ready_set.add(agent.name)
        self.ready.appendleft(agent)

    def kill_agent(self, name: str, delay: float = 0.0) -> bool:
        """Remove an agent (Jason's ``.kill_agent``): its intentions stop, later messages to it are
        undeliverable. With a ``delay`` (seconds) it first gets ``+jag_shutting_down(MS)`` and is removed that
        long after, by its own clock (Jason's ``LocalRuntimeServices.killAgent``). On the loop's thread."""
        if delay > 0:
            agent = self.agents.get(name)
            if agent is None:
                return False
            _shutting_down(agent, delay)
            agent.add_timer(delay, partial(self.kill_agent, name))
            self.wake(agent)
            return True
        agent = self.agents.pop(name, None)
        if agent is None:
            return False
        agent.stopped = True
        agent.events.clear()
        agent.running.clear()
        agent.timers.clear()
        agent.mailbox.clear()
        self._timed.discard(agent)
        if self.directory is not None:
            self.directory.forget(name)
        if self.membership is not None:
            self.membership.left(name)
        return True

    def accepts_plans_from(self, sender: str) -> bool:
        return self.trusted_senders is None or sender in self.trusted_senders or sender in self.agents

    # -- cross-thread entry points
    def wake(self, agent: Agent) -> None:
        if get_ident() == self._loop_thread and not self._sleepers:
            # from the loop's own thread nobody waits to be notified: no lock. A wake from another
            # thread at the same moment may queue the agent twice: one turn with nothing to do.
            if agent.name not in self._ready_set:
                self._ready_set.add(agent.name)
                self.ready.append(agent)
            return
        with self._cond:
            if agent.name not in self._ready_set:
                self._ready_set.add(agent.name)
                self.ready.append(agent)
            if self._sleepers:  # nobody waits while the loop is busy: no notify to pay for
                self._cond.notify()

    def route(self, message: Message) -> bool:
        return self._route_from(None, message)

    def _route_from(self, sender: Agent | None, message: Message) -> bool:
        """``route``, with the signature of ``LocalArch.send`` (which it is, unless overridden): False when no
        agent of that name exists, here or (``remote``) elsewhere (``.send`` then fails, as Jason's)."""
        target = self.agents.get(message.receiver)
        if target is not None:
            if get_ident() == self._loop_thread and not self._sleepers \
                    and type(target.arch).wake is LocalArch.wake:
                # in-process delivery from the loop's thread (Agent.deliver and wake, inlined)
                target.mailbox.append(message)
                if message.sent_at is not None and self._urgent_in_row < URGENT_IN_ROW:
                    # an ask with a timeout, or an answer to an ask: a deadline in wall time runs, which the
                    # receiver on a thread of its own would meet at once (Jason); it goes first, as an idle
                    # agent whose timer is due does (the turns of the agents woken before it come after; at
                    # most URGENT_IN_ROW such turns before one of theirs, so a chain of asks starves nobody)
                    self._urgent_in_row += 1
                    self._urgent.add(message.receiver)
                    self._run_first(target)
                elif message.receiver not in self._ready_set:
                    self._ready_set.add(message.receiver)
                    self.ready.append(target)
                return True
            target.deliver(message)
            return True
        if self.remote is not None and self.remote(message):
            return True
        self.undeliverable += 1
        log.warning("message %s to unknown agent '%s' dropped", message.msg_id, message.receiver)
        return False

    def stop(self, delay: float = 0.0, exit_code: int = 0) -> None:
        """Stop the MAS ``delay`` seconds from now; with a delay, every agent first gets the event
        ``+jag_shutting_down(MS)`` to prepare itself (Jason's ``RunLocalMAS.stopAgs``). A non-zero
        ``exit_code`` (``.stopMAS(D, Code)``) is kept for the process's exit status; the first one wins."""
        if exit_code and not self.exit_code:
            self.exit_code = exit_code
        if delay > 0:
            on_loop = get_ident() == self._loop_thread
            for agent in list(self.agents.values()):
                if on_loop:
                    _shutting_down(agent, delay)
                    self.wake(agent)
                else:   # told by another process (a network thread): in the agent's next turn
                    agent.post_feedback(partial(_shutting_down, agent, delay))
        with self._cond:
            self._stop_at = time.monotonic() + delay
            self._cond.notify()

    def stop_requested(self) -> bool:
        """A stop was asked for (``stop``: a signal, ``.stopMAS``, a launcher), due now or later. For code that waits
        outside ``run`` (an agent process waiting for its peers) and must give up then."""
        return self._stop_at is not None

    def wait_for_work(self, timeout: float | None) -> bool:
        """Block until an agent is ready or a stop is requested (True), or ``timeout`` passes (False).
        For loops that do something while the MAS is idle (e.g. publish status for a launcher)."""
        with self._cond:
            self._sleepers += 1
            try:
                return self._cond.wait_for(lambda: bool(self.ready) or bool(self.busy) or self._stop_at is not None,
                                           timeout)
            finally:
                self._sleepers -= 1

    def print_line(self, name: str, text: str) -> None:
        if self.printer is not None:
            self.printer(name, text)
        else:
            print(f"[{name}] {text}", flush=True)

    # -- the loop
    def idle(self) -> bool:
        return not self.ready and not self.busy and all(a.is_idle() for a in self.agents.values())

    def run(self, timeout: float | None = None, stop_when_idle: bool = True) -> str:
        """Run until ``.stopMAS``, until idle (if asked) or until ``timeout`` seconds. Returns why."""
        outer = self._loop_thread
        self._loop_thread = get_ident()
        try:
            return self._run(timeout, stop_when_idle)
        finally:
            self._loop_thread = outer

    def _run(self, timeout: float | None, stop_when_idle: bool) -> str:
        deadline = None if timeout is None else time.monotonic() + timeout
        ready = self.ready
        busy = self.busy
        ready_set = self._ready_set
        woken_turns = 0  # turns given to woken agents in a row
        timed = self._timed
        timed.update([a for a in self.agents.values() if a.timers])  # a list: a generator is a closure, which
        # the compiled (cpdef, see runtime.pxd) loop cannot hold
        monotonic = time.monotonic
        turn = range(CYCLES_PER_TURN)
        while True:
            if self._stop_at is not None and monotonic() >= self._stop_at:
                self.stopped = True
                return "stopped"
            if deadline is not None and monotonic() >= deadline:
                return "timeout"
            # timers that are due make their agents ready (only agents that have timers are looked at)
            if timed:
                due = []
                for agent in list(timed):
                    if not agent.timers:
                        timed.discard(agent)
                    elif agent.timers[0][0] + agent.timer_lag <= agent.clock() and not (agent.running or agent.events) \
                            and (not ready or ready[0] is not agent):
                        # (a busy agent runs its timers by its own clock, in its turns: Agent.sense)
                        due.append((agent.timers[0][0] + agent.timer_lag, agent))
                if due:
                    # first in line, the earliest first, even if already queued: a .wait or .at that is
                    # due goes on at once, as an agent on a thread of its own would (Jason), not after a
                    # round of every busy agent (with 50 busy agents that round takes seconds)
                    due.sort(key=_when)
                    for _, agent in reversed(due):
                        self._run_first(agent)
            if ready or busy:
                # no lock: a wake from another thread in between either finds the agent still marked
                # ready (and the has_work() check after its turn sees the news) or queues it again.
                # Woken agents first, but a busy one gets every fourth turn (none starves).
                if not busy:  # (the usual case first: a message or a due timer woke it)
                    agent = ready.popleft()
                elif ready and woken_turns < 3:
                    agent = ready.popleft()
                    woken_turns += 1
                else:
                    agent = busy.popleft()
                    woken_turns = 0
                ready_set.discard(agent.name)
                if self._urgent_in_row:  # (see _route_from)
                    urgent = self._urgent
                    if agent.name not in urgent or not ready:
                        self._urgent_in_row = 0  # an agent woken before the urgent ones has its turn, or none waits
                        urgent.clear()
                    else:
                        urgent.discard(agent.name)
                CURRENT.agent = agent  # whose beliefs functions such as .count(Q) read
                started = 0.0
                for i in turn:
                    agent.cycle()  # called on the agent (not a bound method kept aside): compiled, a C call
                    # that still honours a cycle() overridden in a Python subclass
                    if not (agent.events or agent.running or agent.mailbox or agent.feedback) \
                            or self._stop_at is not None or self._yield_turn:
                        self._yield_turn = False
                        break
                    if i & 15 == 15:  # a long turn: the clock is read from its 16th cycle on
                        if i == 15:
                            started = monotonic()
                        elif monotonic() - started > TURN_SECONDS:
                            break  # slow cycles: the others get their turn (timers stay timely)
                if self._yield_to is not None:
                    # the new agent starts at once; its creator takes its turn in the rotation like every
                    # other agent (a creator that loops must not hold the others back, nor be held back)
                    self._run_first(self._yield_to)
                    self._yield_to = None
                if agent.timers:
                    timed.add(agent)  # timers are only set by the agent itself, during its turn
                if agent.events or agent.running or agent.mailbox or agent.feedback:  # has_work()
                    if agent.name not in ready_set:  # (unless woken meanwhile)
                        ready_set.add(agent.name)
                        busy.append(agent)
                elif agent.timers and agent.timers[0][0] + agent.timer_lag <= agent.clock():
                    self.wake(agent)
                continue
            if stop_when_idle and self.idle() and not self._external_pending():
                return "idle"
            # nothing ready: sleep until the next timer, a wake-up, or the deadline
            now = monotonic()
            waits = [_timer_wait(a, now) for a in timed if a.timers]
            if self._stop_at is not None:
                waits.append(self._stop_at - now)
            if deadline is not None:
                waits.append(deadline - now)
            wait = max(0.0, min(waits)) if waits else 0.5
            with self._cond:
                if not self.ready:
                    self._sleepers += 1
                    try:
                        self._cond.wait(min(wait, 0.5))
                    finally:
                        self._sleepers -= 1

    def _external_pending(self) -> bool:
        hook = getattr(self, "external_pending", None)
        return bool(hook()) if hook else False


def _timer_wait(agent: Agent, now: float) -> float:
    """Wall seconds to sleep before ``agent``'s next timer may be due. On an environment's clock (a
    simulator's, which may run slower or faster than wall time) it is looked at again every
    ``CLOCK_POLL_S``: the comparison costs nothing, the agent runs only once its timer is due."""
    clock = agent.clock
    if clock == time.monotonic:
        return agent.timers[0][0] + agent.timer_lag - now
    return min(agent.timers[0][0] + agent.timer_lag - clock(), CLOCK_POLL_S)
