"""Key expressions of the inspector, under the MAS namespace (``agents.transport.keys``)."""
from __future__ import annotations

from agents.transport.keys import check_name, mas_prefix


def state_key(mas: str, agent: str) -> str:
    """Queryable: ``agent``'s mind now (JSON; selector parameter ``summary`` for the team list only)."""
    return f"{mas_prefix(mas)}/inspect/{check_name(agent)}/state"


def state_pattern(mas: str) -> str:
    return f"{mas_prefix(mas)}/inspect/*/state"


def stream_key(mas: str, agent: str) -> str:
    """``agent``'s mind, put when it changes, only while a subscriber matches (someone watches)."""
    return f"{mas_prefix(mas)}/inspect/{check_name(agent)}/stream"


def control_key(mas: str, agent: str) -> str:
    """Queryable: ``pause``/``step``/``resume`` (refused unless the MAS allows it); replies JSON."""
    return f"{mas_prefix(mas)}/inspect/{check_name(agent)}/control"


def robot_percepts_pattern(mas: str) -> str:
    """The robots' percept snapshots (``robot_bridge.zenoh_bridge``): odometry and camera detections."""
    return f"{mas_prefix(mas)}/robot/*/percepts"


def agent_of(key: str) -> str:
    """The agent (or robot) name in ``faultmas/<mas>/inspect/<agent>/...`` or ``.../robot/<robot>/...``."""
    return key.split("/")[3]
