"""``.progress(Step)`` / ``.progress(Step, Detail)``: an agent reports a step of its work to whoever runs it.

A plan marks the steps worth timing (``.progress(fault_detected, no_progress)``); the run that launched
the agents stamps each report with simulated and wall time (``faultmas run`` builds its latency table
from them). The agent's architecture decides where a report goes: ``arch.progress(agent, step, detail)``
when the architecture has that hook (a network agent publishes it on the MAS's control key as
``{"command": "progress", "by", "agent", "step", "detail"}``, signed by the agent in the secure profile,
so a run counts only reports its members signed), else one INFO log line. It never fails a plan.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

from agentspeak.stdlib.registry import internal_action, wrong_arguments
from agentspeak.terms import Literal, to_print_str, to_str

log = logging.getLogger("faultmas.agents")

COMMAND = "progress"


@dataclass(frozen=True)
class ProgressReport:
    """One ``.progress`` call as it travels: who, which step, and the detail as AgentSpeak text."""

    agent: str
    step: str
    detail: str = ""

    def to_fields(self) -> dict:
        return {"agent": self.agent, "step": self.step, "detail": self.detail}

    def to_control(self) -> dict:
        """The control message's fields: ``by`` is the agent, so the secure profile signs it as the agent."""
        return {"by": self.agent, **self.to_fields()}

    @classmethod
    def from_message(cls, message: dict) -> "ProgressReport | None":
        """The report in a control message, or None when it is not a well-formed progress report."""
        fields = [message.get(k, "") for k in ("agent", "step", "detail")]
        if message.get("command") != COMMAND or not all(isinstance(f, str) for f in fields) or not fields[1]:
            return None
        return cls(*fields)

    @staticmethod
    def proved(message: dict) -> bool:
        """Whether the report is signed by the agent it names. Only meaningful where the transport checks
        signatures (the secure profile): it keeps ``by`` only on a control message its signer's key proved,
        and drops it from an unsigned one."""
        return message.get("by") == message.get("agent")


@internal_action(".progress", args=(1, 2))
def progress(ctx, step, detail=None) -> None:
    """Report ``step`` (an atom) with an optional ``detail`` term to the agent's runner."""
    if not isinstance(step, Literal) or step.args:
        raise wrong_arguments(f".progress: the step must be an atom, not {to_str(step)}")
    report = ProgressReport(ctx.agent.name, step.functor, "" if detail is None else to_print_str(detail))
    hook = getattr(ctx.agent.arch, "progress", None)
    if hook is not None:
        hook(ctx.agent, report)
    else:
        log.info("[%s] %s %s", report.agent, report.step, report.detail)
