"""What an agent's observers (``.observe``, ``detection/``) see now, for the inspector's page: each
observer's latest verdict, Obs, the diagnoses and PosAb, and the rules that fired last."""
from __future__ import annotations

import os
from typing import Any


def observers_of(agent: Any) -> list[dict]:
    """One entry per ``.observe`` session of ``agent`` (none when ``detection`` is not installed)."""
    try:
        # the sessions .observe keeps per agent (detection.agent_actions has no public accessor yet)
        from detection.agent_actions import _lock, _observing
    except ImportError:
        return []
    with _lock:
        sessions = [session for session, _ in _observing.get(agent, ())]
    out = []
    for session in sessions:
        last = session.pipeline.last
        update = last.to_json() if last is not None else {}
        verdicts = []
        for name, (verdict, t) in sorted(dict(session.observers.verdicts).items()):
            verdicts.append({"observation": name, "time": t,
                             "holds": None if verdict is None else verdict.holds,
                             "measured": None if verdict is None else verdict.measured,
                             "state": None if verdict is None else verdict.state})
        out.append({"config": os.path.basename(str(session.config.path)), "verdicts": verdicts,
                    "obs": update.get("obs", []), "diagnoses": update.get("diagnoses"),
                    "possibly_faulty": update.get("possibly_faulty"), "fired": update.get("fired", [])})
    return out
