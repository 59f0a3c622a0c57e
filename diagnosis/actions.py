"""What a fired rule does: log, call a registered Python callable, run a command, set a ROS 2
parameter, or post a belief/event to a local agent.

The ROS 2 and agent ends are small protocols so this package imports neither rclpy nor the interpreter:
the ros2 bridge implements ``ParameterSetter``, the MAS wires ``Poster`` to its agents.
"""
from __future__ import annotations

import logging
import subprocess
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Protocol

log = logging.getLogger("faultmas.diagnosis.rules")


class ParameterSetter(Protocol):
    def set_parameter(self, node: str, name: str, value: Any) -> None:
        """Set parameter ``name`` of ROS 2 node ``node`` (raise on failure)."""


class Poster(Protocol):
    def __call__(self, agent_name: str, literal_text: str) -> None:
        """Add the belief or event ``literal_text`` (AgentSpeak syntax, e.g. ``+fault(left_motor)``)."""


@dataclass(frozen=True)
class RuleContext:
    """What a rule saw when it fired."""
    rule: str
    observations: Mapping[str, bool]
    possibly_faulty: frozenset[str]


@dataclass
class ActionEnvironment:
    """The outside world a rule's action may reach; missing parts make the action fail clearly."""
    callables: dict[str, Callable[[RuleContext], Any]] = field(default_factory=dict)
    parameters: ParameterSetter | None = None
    post: Poster | None = None


class ActionError(RuntimeError):
    """An action could not run (missing callable or bridge, command failed or timed out)."""


@dataclass(frozen=True)
class LogAction:
    message: str

    def run(self, ctx: RuleContext, env: ActionEnvironment) -> str:
        text = self.message.format(rule=ctx.rule, possibly_faulty=", ".join(sorted(ctx.possibly_faulty)))
        log.warning("%s", text)
        return text


@dataclass(frozen=True)
class CallAction:
    name: str

    def run(self, ctx: RuleContext, env: ActionEnvironment) -> Any:
        fn = env.callables.get(self.name)
        if fn is None:
            raise ActionError(f"rule {ctx.rule}: no callable registered as {self.name!r}")
        return fn(ctx)


@dataclass(frozen=True)
class CommandAction:
    """An external program: an argument list, never a shell; killed after ``timeout`` seconds."""
    argv: tuple[str, ...]
    timeout: float = 10.0

    def run(self, ctx: RuleContext, env: ActionEnvironment) -> subprocess.CompletedProcess:
        try:
            done = subprocess.run(list(self.argv), capture_output=True, text=True, timeout=self.timeout,
                                  shell=False, check=False)
        except subprocess.TimeoutExpired:
            raise ActionError(f"rule {ctx.rule}: {self.argv[0]} did not finish in {self.timeout} s") from None
        except OSError as exc:
            raise ActionError(f"rule {ctx.rule}: cannot run {self.argv[0]}: {exc.strerror}") from None
        if done.returncode != 0:
            raise ActionError(f"rule {ctx.rule}: {self.argv[0]} exited with {done.returncode}: {done.stderr.strip()}")
        return done


@dataclass(frozen=True)
class SetParameterAction:
    node: str
    name: str
    value: Any

    def run(self, ctx: RuleContext, env: ActionEnvironment) -> None:
        if env.parameters is None:
            raise ActionError(f"rule {ctx.rule}: no ROS 2 parameter bridge to set {self.node} {self.name}")
        env.parameters.set_parameter(self.node, self.name, self.value)


@dataclass(frozen=True)
class PostAction:
    agent: str
    literal: str

    def run(self, ctx: RuleContext, env: ActionEnvironment) -> None:
        if env.post is None:
            raise ActionError(f"rule {ctx.rule}: no agent to post {self.literal!r} to")
        env.post(self.agent, self.literal)


Action = LogAction | CallAction | CommandAction | SetParameterAction | PostAction
