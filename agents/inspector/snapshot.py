"""An agent's mind as JSON-ready dicts: what the inspector page shows (Jason's mind inspector).

Read from a thread other than the agent's (the Zenoh query thread): every container is copied in one
C-level call (``list(deque)``, ``dict(b)``), which the interpreter lock makes atomic, before it is
walked; terms are immutable. A copy can still meet a container changed mid-way: ``take`` retries.
While the agent is paused (``pause``) its thread is blocked, so what is read is one consistent state.
"""
from __future__ import annotations

import os
import time
from typing import Any, Callable

from agentspeak.terms import resolve, to_str

MAX_BELIEFS = 2000
"""Beliefs sent per snapshot (a belief base of robots' logs can be huge; the page says when cut)."""
MAX_BINDINGS = 40


def take(read: Callable[[], dict], attempts: int = 5) -> dict:
    """``read()``, again when a container changed under it (``RuntimeError``: changed size)."""
    for attempt in range(attempts):
        try:
            return read()
        except RuntimeError:
            if attempt == attempts - 1:
                raise
            time.sleep(0.001)
    raise AssertionError("unreachable")


def robot_of(agent: Any) -> str | None:
    """The name of the robot bridge the agent drives (``zenoh``, ``sim``, ``ros2``), if any."""
    arch = agent.arch
    body = getattr(arch, "body", None) or arch
    bridge = getattr(body, "bridge", None)
    if bridge is None or not hasattr(bridge, "act"):
        return None
    return getattr(bridge, "name", None) or type(bridge).__name__


def intentions_of(agent: Any) -> list:
    """Every intention: running ones first (the next to act leads), then suspended, then those
    waiting for their own subgoal's event."""
    seen: dict[int, Any] = {}
    for intention in list(agent.running):
        seen.setdefault(intention.id, intention)
    for intention in list(agent.suspended.values()):
        seen.setdefault(intention.id, intention)
    for event in list(agent.events):
        if event.intention is not None:
            seen.setdefault(event.intention.id, event.intention)
    return [i for i in seen.values() if not i.dropped]


def _where(source_file: str, line: int) -> str:
    """``file.asl:line``; plans of no file (the interpreter's own, e.g. for ``askOne``) are built-in."""
    return f"{os.path.basename(source_file)}:{line}" if source_file else "built-in"


def _intended_means(im: Any) -> dict:
    bindings = dict(im.b)
    frames = list(im.frames)
    frame = frames[-1] if frames else None
    step = None
    if frame is not None and frame.pc < len(frame.body):
        step = str(frame.body[frame.pc])
    shown = {}
    for var, value in list(bindings.items())[:MAX_BINDINGS]:
        shown[to_str(var)] = to_str(resolve(value, bindings))
    plan = im.plan
    return {"trigger": str(plan.trigger), "event": to_str(resolve(im.event_literal, bindings)),
            "label": to_str(plan.label) if plan.label is not None else None,
            "source": _where(plan.source_file, plan.line), "step": step,
            "pc": frame.pc if frame is not None else None, "depth": len(frames), "bindings": shown}


def _intention(intention: Any) -> dict:
    stack = list(intention.stack)
    return {"id": intention.id, "state": intention.suspended or "running",
            "stack": [_intended_means(im) for im in reversed(stack)]}  # top of the stack first


def top_plan(agent: Any) -> str | None:
    """The top plan of the intention that acts next (the team list shows it)."""
    for intention in intentions_of(agent):
        stack = list(intention.stack)
        if stack:
            im = stack[-1]
            return to_str(resolve(im.event_literal, dict(im.b))) if im.event_literal is not None \
                else str(im.plan.trigger)
    return None


def summary(agent: Any, paused: bool = False) -> dict:
    """What the team list shows of one agent."""
    def read() -> dict:
        return {"agent": agent.name, "cycles": agent.cycles, "paused": paused, "robot": robot_of(agent),
                "top": top_plan(agent), "intentions": len(intentions_of(agent)), "beliefs": len(agent.bb),
                "events": len(agent.events), "source": os.path.basename(agent.source_file or "")}
    return take(read)


def mind(agent: Any, *, paused: bool = False, control: bool = False, plans: bool = False,
         messages: list | None = None, diagnoses: list | None = None) -> dict:
    """The whole mind of ``agent`` now; ``plans``: with the plan library (it rarely changes)."""
    def read() -> dict:
        beliefs = [to_str(b) for b in list(agent.bb.literals())[:MAX_BELIEFS]]
        state = summary(agent, paused)
        state.update({
            "control": control,
            "beliefs": beliefs, "beliefs_cut": max(0, len(agent.bb) - len(beliefs)),
            "rules": [str(r) for r in list(agent.bb.rules())],
            "pending_events": [{"trigger": str(e.trigger),
                                "intention": e.intention.id if e.intention is not None else None}
                               for e in list(agent.events)],
            "intention_stacks": [_intention(i) for i in intentions_of(agent)],
            "mailbox": len(agent.mailbox),
            "dropped": dict(agent.dropped),
            "messages": messages or [],
            "diagnoses": diagnoses or [],
        })
        if plans:
            state["plans"] = [{"trigger": str(p.trigger), "label": to_str(p.label) if p.label is not None else None,
                               "source": _where(p.source_file, p.line), "path": p.source_file, "text": str(p)}
                              for p in list(agent.plans)]
        return state
    return take(read)
