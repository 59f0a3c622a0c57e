"""Run AgentSpeak source in a LocalRuntime and return what it printed, so tests compare lines exactly."""
from __future__ import annotations

import logging

from agentspeak.runtime import LocalRuntime


def run_mas(agents: dict[str, str], timeout: float = 5.0, stop_when_idle: bool = True) -> list[str]:
    """Run several agents (name -> source) together; return every printed line as ``[name] text``."""
    lines: list[str] = []
    runtime = LocalRuntime(printer=lambda name, text: lines.append(f"[{name}] {text}"))
    for name, source in agents.items():
        runtime.add_agent(name, source)
    runtime.run(timeout=timeout, stop_when_idle=stop_when_idle)
    return lines


def run_asl(source: str, name: str = "ag", timeout: float = 5.0) -> list[str]:
    """Run one agent until it is idle, stopped or ``timeout``; return the printed text (no name prefix)."""
    prefix = f"[{name}] "
    return [line[len(prefix):] for line in run_mas({name: source}, timeout=timeout)]


def run_asl_logged(source: str, caplog, name: str = "ag", timeout: float = 5.0) -> tuple[list[str], list[str]]:
    """Like ``run_asl`` but also return the warnings the interpreter logged (what goes to stderr)."""
    with caplog.at_level(logging.WARNING, logger="faultmas"):
        out = run_asl(source, name, timeout)
    return out, [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
