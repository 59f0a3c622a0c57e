"""The diagnoser as AgentSpeak internal actions (loaded through the ``faultmas.internal_actions`` entry point).

* ``.diagnose(Model, Observations, Diagnoses)`` and ``.diagnose(Model, Observations, Diagnoses, Options)``:
  ``Model`` is a path (string, relative to the agent's .asl file) or the name of a model shipped in
  ``plans/`` (e.g. ``turtlebot_hardware``); ``Observations`` a list of literals (``moved``, ``~moved``,
  ``hz(scan)``); ``Diagnoses`` gets a list of lists of component atoms, smallest first (``[[]]``: no fault
  is needed to explain what was observed; ``[]``: nothing explains it). ``Options`` is a list such as
  ``[max_card(2), timeout(5)]`` (seconds).
* ``.possibly_faulty(Model, Observations, Components)``: the components that are faulty in some
  minimum-cardinality diagnosis (PosAb), without enumerating every diagnosis.

Both solve on a worker thread: only the calling intention waits; the agent's other intentions go on.
The last calls of an agent, with their inputs and results, are kept on it as ``diagnosis_calls`` (the
inspector's page shows them).
"""
from __future__ import annotations

import atexit
import os
import threading
import time
from collections import deque
from importlib import resources

from agentspeak.stdlib.registry import IAError, Suspend, internal_action, wrong_arguments
from agentspeak.terms import Literal, is_ground, list_items, make_list, to_str

_lock = threading.Lock()
_service = None
KEPT_CALLS = 20


def service():
    """The process's DiagnosisService (a cache of loaded models and their solvers)."""
    global _service
    with _lock:
        if _service is None:
            from diagnosis.service import DiagnosisService
            _service = DiagnosisService()
            atexit.register(_service.close)
        return _service


def model_path(agent, model) -> str:
    name = model.functor if isinstance(model, Literal) and not model.args else model
    if not isinstance(name, str):
        raise wrong_arguments(f"a diagnosis model is a path or a name, not {to_str(model)}")
    candidates = []
    if os.path.isabs(name):
        candidates.append(name)
    else:
        base = os.path.dirname(agent.source_file) if agent.source_file else "."
        candidates.append(os.path.join(base, name))
        shipped = resources.files("plans")
        for suffix in ("", ".yaml", ".bench"):
            candidates.append(str(shipped.joinpath(name + suffix)))
    for path in candidates:
        if os.path.isfile(path):
            return path
    raise IAError("ia_failed", f"diagnosis model {name!r} not found (looked in: {', '.join(candidates)})")


def observations(term) -> dict[str, bool]:
    try:
        items = list_items(term)
    except TypeError:
        raise wrong_arguments(f"observations must be a list of literals, not {to_str(term)}") from None
    out: dict[str, bool] = {}
    for item in items:
        if not isinstance(item, Literal) or not is_ground(item):
            raise wrong_arguments(f"observation {to_str(item)} is not a ground literal")
        plain = Literal(item.functor, item.args)
        name = to_str(plain)
        value = not item.neg
        if out.get(name, value) != value:
            raise wrong_arguments(f"observation {name} is given both as true and as false")
        out[name] = value
    return out


def _options(term) -> dict:
    opts: dict = {}
    for item in list_items(term) if term is not None else ():
        if isinstance(item, Literal) and len(item.args) == 1 and item.functor in ("max_card", "timeout", "max_count"):
            opts[item.functor] = item.args[0]
        elif isinstance(item, Literal) and item.functor == "min_card_only" and not item.args:
            opts["min_card_only"] = True
        else:
            raise wrong_arguments(f".diagnose: unknown option {to_str(item)}")
    return opts


@internal_action(".diagnose", args=(3, 4))
def diagnose(ctx, model, obs, result, options=None):
    """All minimal diagnoses of ``model`` given ``obs``, as a list of lists of component atoms."""
    path = model_path(ctx.agent, model)
    seen = observations(obs)
    future = service().submit(path, seen, **_options(options))
    _record(ctx.agent, ".diagnose", path, seen, future, lambda res: [sorted(d) for d in res.diagnoses])

    def on_result(c, res) -> bool:
        return c.unify(result, make_list([make_list([Literal(x) for x in d]) for d in res.diagnoses]))
    return Suspend(future=future, on_result=on_result, reason="diagnosing")


@internal_action(".possibly_faulty", args=3)
def possibly_faulty(ctx, model, obs, result):
    """PosAb: the components faulty in some minimum-cardinality diagnosis."""
    path = model_path(ctx.agent, model)
    seen = observations(obs)
    future = service().submit_possibly_faulty(path, seen)
    _record(ctx.agent, ".possibly_faulty", path, seen, future, list)

    def on_result(c, comps) -> bool:
        return c.unify(result, make_list([Literal(x) for x in comps]))
    return Suspend(future=future, on_result=on_result, reason="diagnosing")


def _record(agent, action: str, path: str, seen: dict[str, bool], future, result_of) -> None:
    """Keep this call on the agent (``agent.diagnosis_calls``, the last ``KEPT_CALLS``), its result
    filled in when the solver answers."""
    calls = getattr(agent, "diagnosis_calls", None)
    if calls is None:
        calls = agent.diagnosis_calls = deque(maxlen=KEPT_CALLS)
    entry = {"t": time.time(), "action": action, "model": os.path.basename(path), "observations": dict(seen),
             "state": "running", "result": None}
    calls.append(entry)

    def done(f) -> None:
        try:
            entry["result"] = result_of(f.result())
            entry["state"] = "done"
        except BaseException as exc:  # a failed or cancelled solve is shown with its reason
            entry["result"] = str(exc) or type(exc).__name__
            entry["state"] = "failed"
    future.add_done_callback(done)
