"""Observers for agents (loaded through the ``faultmas.internal_actions`` entry point).

* ``.observe(Config)`` / ``.observe(Config, Options)``: start observing for this agent, in the
  background (the action succeeds at once). ``Config`` is an observer configuration (a path, relative
  to the agent's .asl file); ``Options`` a list of ``model(Path)``, ``rules(Path)``, ``bag(Path)``
  (replay a recorded bag instead of watching the live ROS 2 graph) and ``domain(N)`` (ROS_DOMAIN_ID).
* Each change becomes the percept ``observation(Name, true|false)``, e.g. ``observation(hz(scan), false)``
  (the previous value of the same observation is removed), so ``+observation(hz(scan), false)`` triggers
  a plan. A rule's ``post`` action addressed to this agent adds its literal (``+fault(x)``,
  ``+!repair(x)``).
* ``.observations(Obs, PosAb)``: the current Obs as a list of literals (``[hz(pose), ~hz(scan)]``) and
  PosAb as a list of components (``[]`` without a model).

This module depends on the interpreter (``agentspeak``) and on ``detection``, never on ``agents``.
"""
from __future__ import annotations

import atexit
import logging
import os
import threading
from functools import partial

from agentspeak.beliefs import SOURCE_PERCEPT
from agentspeak.errors import SourceError
from agentspeak.program import ACHIEVE, ADD, BEL, DEL, Trigger
from agentspeak.stdlib.registry import IAError, internal_action, wrong_arguments
from agentspeak.terms import Literal, list_items, make_list, to_str

log = logging.getLogger("faultmas.detection")
PERCEPT = "observation"
OPTIONS = ("model", "rules", "bag", "domain")
TRUE, FALSE = Literal("true"), Literal("false")

_observing: dict[object, list] = {}     # agent -> [(session, closer)]; the compiled Agent takes no weakref
_lock = threading.Lock()


def _path(agent, term, what: str) -> str:
    text = term if isinstance(term, str) else (term.functor if isinstance(term, Literal) and not term.args else None)
    if not isinstance(text, str):
        raise wrong_arguments(f"{what} is a path, not {to_str(term)}")
    if not os.path.isabs(text) and agent.source_file and os.path.exists(os.path.dirname(agent.source_file) or "."):
        text = os.path.join(os.path.dirname(agent.source_file), text)
    return text


def _options(agent, term) -> dict:
    out: dict = {}
    for item in list_items(term) if term is not None else ():
        if not (isinstance(item, Literal) and len(item.args) == 1 and item.functor in OPTIONS):
            raise wrong_arguments(f".observe: unknown option {to_str(item)}; expected {', '.join(o + '(...)' for o in OPTIONS)}")
        value = item.args[0]
        out[item.functor] = value if item.functor == "domain" else _path(agent, value, item.functor)
    return out


def observation_percept(name: str, holds: bool) -> Literal:
    """``observation(hz(scan), false)`` with ``source(percept)``."""
    from agentspeak.parser import parse_term
    return Literal(PERCEPT, (parse_term(name), TRUE if holds else FALSE), (SOURCE_PERCEPT,))


def _perceive(agent, update) -> None:
    """In the agent's sense phase: replace each changed observation's percept."""
    for o in update.changed:
        old = observation_percept(o.name, not o.holds)
        removed = agent.bb.remove(old)
        if removed is not None:
            agent.post_external(Trigger(DEL, BEL, removed))
        added = agent.bb.add(observation_percept(o.name, o.holds))
        if added is not None:
            agent.post_external(Trigger(ADD, BEL, added))


def _post(agent, name: str, text: str) -> None:
    """A rule's ``post`` action: ``+b``, ``-b`` or ``+!g`` for this agent."""
    from diagnosis.actions import ActionError
    from agentspeak.parser import parse_literal

    if name != agent.name:
        raise ActionError(f"post: agent {name!r} is not the observing agent {agent.name!r}")
    text = text.strip()
    if text.startswith("+!"):
        kind, op, body = ACHIEVE, ADD, text[2:]
    elif text[:1] in "+-":
        kind, op, body = BEL, (ADD if text[0] == "+" else DEL), text[1:]
    else:
        kind, op, body = BEL, ADD, text
    lit = parse_literal(body)

    def apply() -> None:
        if kind == ACHIEVE:
            agent.post_external(Trigger(ADD, ACHIEVE, lit), force=True)
        elif op == ADD:
            added = agent.bb.add(lit.add_annot(SOURCE_PERCEPT) if not lit.annots else lit)
            if added is not None:
                agent.post_external(Trigger(ADD, BEL, added))
        else:
            removed = agent.bb.remove(lit.add_annot(SOURCE_PERCEPT) if not lit.annots else lit)
            if removed is not None:
                agent.post_external(Trigger(DEL, BEL, removed))
    # rules fire before the pipeline's listeners run, so the percept of the observation that made this
    # rule fire is queued after us: one more hop puts the rule's event after the percept's
    agent.post_feedback(lambda: agent.post_feedback(apply))


@internal_action(".observe", args=(1, 2))
def observe(ctx, config, options=None):
    """Start observers, diagnosis and rules for this agent; changes arrive as percepts."""
    from diagnosis.actions import ActionEnvironment
    from detection.session import open_session

    agent = ctx.agent
    opts = _options(agent, options)
    environment = ActionEnvironment(post=partial(_post, agent))
    try:
        session = open_session(_path(agent, config, "the configuration"), opts.get("model"), opts.get("rules"),
                               environment)
    except SourceError as exc:
        raise IAError("ia_failed", str(exc)) from None
    session.pipeline.add_listener(lambda update: agent.post_feedback(partial(_perceive, agent, update)))
    agent.pending_futures += 1          # observing: things will happen by themselves, the agent is not idle
    if "bag" in opts:
        closer = _replay_in_background(session, opts["bag"], agent)
    else:
        closer = _watch_live(session, environment, opts.get("domain"))
    with _lock:
        _observing.setdefault(agent, []).append((session, closer))
    return True


def _replay_in_background(session, bag: str, agent):
    from detection.session import replay_bag

    def done() -> None:
        agent.pending_futures -= 1

    def run() -> None:
        try:
            replay_bag(session, bag)
        except SourceError as exc:
            log.error("%s", exc)
        finally:
            agent.post_feedback(done)       # after the last percepts: the replay is over
    thread = threading.Thread(target=run, daemon=True, name="faultmas-observe-bag")
    thread.start()
    return lambda: thread.join(5.0)


def _watch_live(session, environment, domain):
    from robot_bridge.ros2.runtime import RosUnavailable

    try:
        from detection.taps.ros2 import Ros2Tap, TapError
        from detection.taps.ros2_parameters import Ros2Parameters
        tap = Ros2Tap(session.config, session.observers, session.pipeline.observe, domain_id=domain)
    except (RosUnavailable, ImportError) as exc:
        raise IAError("ia_failed", f".observe: {exc}") from None
    except TapError as exc:
        raise IAError("ia_failed", f".observe: {session.config.path}: {exc}") from None
    environment.parameters = Ros2Parameters(domain)
    tap.start()

    def close() -> None:
        tap.close()
        environment.parameters.close()
    return close


@internal_action(".observations", args=2)
def observations(ctx, obs, posab):
    """The current Obs (literals) and PosAb (components) of this agent's observers."""
    with _lock:
        sessions = [s for s, _ in _observing.get(ctx.agent, ())]
    literals, faulty = [], set()
    for session in sessions:
        last = session.pipeline.last
        for o in session.pipeline.observations.values():
            literals.append(o.literal)
        if last is not None and last.possibly_faulty:
            faulty |= last.possibly_faulty
    from agentspeak.parser import parse_literal
    return (ctx.unify(obs, make_list([parse_literal(t) for t in sorted(literals)]))
            and ctx.unify(posab, make_list([Literal(c) for c in sorted(faulty)])))


def _close_all() -> None:
    with _lock:
        everything = [item for items in _observing.values() for item in items]
        _observing.clear()
    for session, closer in everything:
        try:
            closer()
        finally:
            session.close()


atexit.register(_close_all)
