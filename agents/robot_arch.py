"""An agent architecture that drives a robot through a bridge (``robot_bridge``).

Percepts come from ``bridge.percepts()`` each reasoning cycle and become literals with
``source(percept)`` (Jason's BUF diffs them into +p/-p events); an environment action becomes an
``Action`` for ``bridge.act`` and suspends only its intention until the completion arrives, which
fails the action with the bridge's reason (``no_progress``, ``timeout``, ``unknown_action``...). The
robot's clock, when it has one, is the agent's (``environment_clock``).
"""
from __future__ import annotations

import logging
from concurrent.futures import Future

from agentspeak.runtime import LocalArch
from agentspeak.terms import Literal, Term, list_items, make_list
from robot_bridge.protocol import Action, Completion, Percept, RobotBridge

log = logging.getLogger("faultmas.agents")


def to_term(value: object) -> Term:
    """A bridge value as an AgentSpeak term: str -> atom, bool -> true/false, tuple -> list."""
    if isinstance(value, bool):
        return Literal("true" if value else "false")
    if isinstance(value, (int, float)):
        return value
    if isinstance(value, str):
        return Literal(value)
    if isinstance(value, (tuple, list)):
        return make_list([to_term(v) for v in value])
    raise TypeError(f"cannot turn {value!r} into an AgentSpeak term")


def from_term(term: Term) -> object:
    """An AgentSpeak term as a bridge value (atoms and strings -> str, lists -> tuple)."""
    if isinstance(term, Literal):
        if term.args:
            raise TypeError(f"structured argument {term} is not supported by bridges")
        return term.functor
    if isinstance(term, (int, float, str)):
        return term
    try:
        return tuple(from_term(t) for t in list_items(term))
    except TypeError:
        raise TypeError(f"argument {term} is not a value a bridge understands") from None


def percept_literal(p: Percept) -> Literal:
    return Literal(p.name, tuple(to_term(a) for a in p.args))


class RobotArch(LocalArch):
    """A ``LocalArch`` whose environment is one robot bridge."""

    def __init__(self, runtime, bridge: RobotBridge, on_progress=None, **kwargs) -> None:
        super().__init__(runtime, **kwargs)
        self.bridge = bridge
        self.on_progress = on_progress
        """``on_progress(report)``: where ``.progress`` reports go (``agents.progress``); None: logged."""

    def progress(self, agent, report) -> None:
        if self.on_progress is not None:
            self.on_progress(report)
        else:
            log.info("[%s] %s %s", report.agent, report.step, report.detail)

    def perceive(self, agent) -> list[Literal] | None:
        return [percept_literal(p) for p in self.bridge.percepts()]

    def environment_clock(self):
        """The robot's clock, when it has one (a simulated robot: simulated time): the agent's waits and
        timeouts follow it, so a plan's ``.wait(300)`` lasts 0.3 s of the robot's time however fast the
        simulator runs; None for a robot in wall time."""
        return self.bridge.clock if self.bridge.clock() is not None else None

    def act(self, agent, action: Literal) -> "Future | bool":
        try:
            args = tuple(from_term(a) for a in action.args)
        except TypeError:
            return _done(Completion.failure("bad_args", str(action)))
        future = self.bridge.act(Action(action.functor, args))
        result: Future = Future()

        def relay(f: Future) -> None:
            try:
                result.set_result(f.result())
            except Exception as exc:  # a broken bridge fails the action, with its reason
                result.set_result(Completion.failure("bridge_error", str(exc)))
            agent.arch.wake(agent)
        future.add_done_callback(relay)
        return result


def _done(c: Completion) -> Future:
    f: Future = Future()
    f.set_result(c)
    return f
