"""The bridge protocol: the one small interface through which an agent drives a robot.

A bridge knows nothing of AgentSpeak. Actions arrive and percepts leave as plain Python values
(`Action`, `Percept`); the agent architecture (``agents/``) converts them from and to AgentSpeak
literals (an argument of type ``str`` is an atom, ``int``/``float`` a number, a tuple a list).
Keeping the interpreter out of this layer lets ROS nodes and the simulator run without it.

Completion means the motion finished (as in the seed paper's code), not "message sent": ``act``
returns a future that resolves when the robot says the action is done, or failed and why. A bridge
must resolve every future: an unknown action, bad arguments or a robot that does not answer within
its timeout fail at once with a reason (``unknown_action``, ``bad_args``, ``timeout``).
"""
from __future__ import annotations

import abc
import itertools
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import ClassVar, Union

Value = Union[int, float, str, bool, tuple]
"""An action or percept argument: a number, an atom (``str``), a boolean or a tuple (a list)."""

_action_ids = itertools.count(1)


@dataclass(frozen=True)
class Action:
    """An action requested by an agent, e.g. ``Action("move", (0.5,))`` for ``move(0.5)``."""

    name: str
    args: tuple[Value, ...] = ()
    id: int = field(default_factory=lambda: next(_action_ids), compare=False)

    def __str__(self) -> str:
        return f"{self.name}({', '.join(map(str, self.args))})" if self.args else self.name


@dataclass(frozen=True)
class Completion:
    """How an action ended. ``reason`` is a short atom-like word when ``ok`` is false."""

    ok: bool
    reason: str | None = None
    detail: str = ""

    @classmethod
    def success(cls) -> "Completion":
        return cls(True)

    @classmethod
    def failure(cls, reason: str, detail: str = "") -> "Completion":
        return cls(False, reason, detail)


@dataclass(frozen=True)
class Percept:
    """Something the robot perceives now, e.g. ``Percept("odom", (1.2, 0.0, 90.0))``.

    The names and arguments every bridge uses are listed in ``robot_bridge.percepts``.
    """

    name: str
    args: tuple[Value, ...] = ()


class RobotBridge(abc.ABC):
    """Base class of every bridge (found by name through the ``faultmas.robot_bridges`` entry points).

    Life cycle, as in py_trees: ``__init__`` does no I/O (a bridge can be built offline);
    ``setup(timeout)`` opens middleware connections and raises ``TimeoutError`` naming what did not
    answer; ``shutdown()`` releases them and fails every pending action with reason ``shutdown``.
    """

    name: ClassVar[str] = "abstract"
    known_options: ClassVar[dict[str, str] | None] = None
    """Option name -> meaning, for a bridge that reads ``**options`` itself; None: its ``__init__``'s keyword
    parameters are its options (``robot_bridge.registry.known_options``). Other keys are refused by name."""

    def __init__(self, robot: str, **options: object) -> None:
        self.robot = robot
        self.options = options

    @classmethod
    def for_team(cls, robots: list[str], **options: object) -> "dict[str, RobotBridge]":
        """One bridge per robot of a team, not yet set up. Each robot is its own by default; a bridge whose
        robots must share something (the simulator: one world) overrides this."""
        return {robot: cls(robot, **options) for robot in robots}

    @abc.abstractmethod
    def setup(self, timeout: float = 5.0) -> None:
        """Connect to the robot (or start the simulated one)."""

    @abc.abstractmethod
    def act(self, action: Action) -> "Future[Completion]":
        """Start ``action``; the future resolves when it has finished or failed. Never blocks."""

    @abc.abstractmethod
    def percepts(self) -> list[Percept]:
        """The robot's current percepts (a snapshot; the agent diffs successive snapshots)."""

    @abc.abstractmethod
    def shutdown(self) -> None:
        """Stop the robot, release connections, fail pending actions with reason ``shutdown``."""

    def clock(self) -> float | None:
        """The robot's own time in seconds (a simulator's simulated time), or None: the robot lives in wall
        time (a real robot). An agent counts its waits and timeouts in this clock when there is one
        (``robot_bridge.clock``), as a ROS 2 node with ``use_sim_time`` follows ``/clock``."""
        return None


def completed(completion: Completion) -> "Future[Completion]":
    """A future that is already resolved: for actions that fail (or succeed) at once."""
    future: Future[Completion] = Future()
    future.set_result(completion)
    return future
