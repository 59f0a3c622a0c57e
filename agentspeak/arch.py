"""The agent architecture: everything between an agent and the world (Jason's AgArch).

Override what you need: ``perceive`` (current percepts, or None when nothing changed), ``act``
(start an environment action; return a ``Future`` resolving to success/failure, or a bool at once,
or None for "no environment"), ``send`` (deliver a message), ``print_line``, ``all_names``,
``stop_mas``, ``wake`` (something arrived for this agent: schedule it) and ``environment_clock`` (the
environment's own time, which the agent's timers then follow). No I/O in ``__init__``.
"""
from __future__ import annotations

import sys
from concurrent.futures import Future
from typing import Any, Callable, TextIO

from agentspeak.terms import Literal


class AgentArch:
    """A stand-alone architecture: prints to stdout, has no environment and no other agents."""

    def __init__(self, out: TextIO | None = None, on_print: Callable[[str, str], None] | None = None) -> None:
        self.out = out
        self.on_print = on_print

    def perceive(self, agent: Any) -> list[Literal] | None:
        return None

    def act(self, agent: Any, action: Literal) -> "Future | bool | None":
        return None

    def send(self, agent: Any, message: Any) -> None:
        raise RuntimeError(f"agent {agent.name} has no other agents to talk to")

    def all_names(self, agent: Any) -> list[str]:
        return [agent.name]

    def print_line(self, agent: Any, text: str) -> None:
        if self.on_print is not None:
            self.on_print(agent.name, text)
            return
        out = self.out or sys.stdout
        out.write(f"[{agent.name}] {text}\n")
        out.flush()

    def stop_mas(self, agent: Any, delay: float = 0.0, exit_code: int = 0) -> None:
        agent.stopped = True

    def environment_clock(self) -> Callable[[], float] | None:
        """The clock (seconds) of this agent's environment, if it has one of its own: a simulator's
        simulated time. The agent's timers (``.wait``, ``.at``, answer timeouts, deadlines) then count in
        it, as a ROS 2 node with ``use_sim_time`` follows the simulator; None (the default): wall time,
        as in Jason. Asked when the agent gets this architecture."""
        return None

    def wake(self, agent: Any) -> None:
        """Called (possibly from another thread) when the agent has new work."""
