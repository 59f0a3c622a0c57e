"""The Zenoh key expressions of a MAS: everything lives under ``faultmas/<mas>/`` so two MAS on one
network never see each other's traffic, and an access-control rule can name one MAS by prefix."""
from __future__ import annotations

import base64

from agents.transport.envelope import is_valid_name

ROOT = "faultmas"


def check_name(name: str, what: str = "agent name") -> str:
    """Return ``name`` if it can be a key-expression chunk, else raise ``ValueError`` saying why."""
    if not is_valid_name(name):
        raise ValueError(f"invalid {what} {name!r}: it must be non-empty, without '/', '*', '$', '?', '#' "
                         "or white space")
    return name


def mas_prefix(mas: str) -> str:
    return f"{ROOT}/{check_name(mas, 'MAS name')}"


def inbox_key(mas: str, agent: str) -> str:
    """Where speech acts for ``agent`` are put."""
    return f"{mas_prefix(mas)}/agent/{check_name(agent)}/inbox"


def alive_key(mas: str, agent: str) -> str:
    """The liveliness token of ``agent``: present while its process and session are up."""
    return f"{mas_prefix(mas)}/alive/{check_name(agent)}"


def alive_pattern(mas: str) -> str:
    return f"{mas_prefix(mas)}/alive/*"


def created_key(mas: str, agent: str, creator: str) -> str:
    """The liveliness token that says ``agent`` was made at run time by ``creator`` (``.create_agent``,
    ``.clone``): a member of the MAS for the other processes while its creator is (``trust.is_member``)."""
    return f"{mas_prefix(mas)}/created/{check_name(agent)}/{check_name(creator)}"


def created_pattern(mas: str) -> str:
    return f"{mas_prefix(mas)}/created/*/*"


def claim_key(mas: str, name: str) -> str:
    """The queryable that answers with the claims a process holds on ``name``, a name being made at run time or
    made (``name_claims``: how two processes that make one name at once do not both get it)."""
    return f"{mas_prefix(mas)}/claim/{check_name(name)}"


def claim_pattern(mas: str) -> str:
    return f"{mas_prefix(mas)}/claim/*"


def control_key(mas: str) -> str:
    """MAS-wide commands (``stop``), seen by every process of the MAS."""
    return f"{mas_prefix(mas)}/control"


def status_key(mas: str, agent: str) -> str:
    """Idle/busy state and message counters of ``agent`` (put on change, and queryable)."""
    return f"{mas_prefix(mas)}/status/{check_name(agent)}"


def status_pattern(mas: str) -> str:
    return f"{mas_prefix(mas)}/status/*"


def heartbeat_key(mas: str, agent: str) -> str:
    """The secure profile's signed heartbeats of ``agent`` (``proved_presence``: what proves its token)."""
    return f"{mas_prefix(mas)}/heartbeat/{check_name(agent)}"


def heartbeat_pattern(mas: str) -> str:
    return f"{mas_prefix(mas)}/heartbeat/*"


def last_chunk(key: str) -> str:
    """The agent name at the end of an ``alive``/``status`` key."""
    return key.rsplit("/", 1)[-1]


def df_key(mas: str, agent: str) -> str:
    """The queryable that answers with the services ``agent`` has registered (``.df_register``)."""
    return f"{mas_prefix(mas)}/df/{check_name(agent)}"


def df_pattern(mas: str) -> str:
    return f"{mas_prefix(mas)}/df/*"


def service_chunk(service: str) -> str:
    """A service (any text, e.g. ``sell(book)``) as one key chunk: ``s`` + its UTF-8 in unpadded base64url."""
    return "s" + base64.urlsafe_b64encode(service.encode()).rstrip(b"=").decode()


def subscribes_key(mas: str, agent: str, service: str) -> str:
    """The liveliness token of one subscription (``.df_subscribe``): present while ``agent`` wants to
    hear of the providers of ``service`` and its process is up."""
    return f"{mas_prefix(mas)}/subscribes/{check_name(agent)}/{service_chunk(service)}"


def subscribes_pattern(mas: str) -> str:
    return f"{mas_prefix(mas)}/subscribes/*/*"


def subscription_of(key: str) -> tuple[str, str]:
    """(agent, service) of a ``subscribes`` key (``ValueError`` if the service chunk is not ours)."""
    agent, chunk = key.rsplit("/", 2)[-2:]
    if not chunk.startswith("s"):
        raise ValueError(f"not a service chunk: {chunk[:40]!r}")
    data = chunk[1:]
    return agent, base64.urlsafe_b64decode(data + "=" * (-len(data) % 4)).decode()
