"""What an outsider with a key pair of its own tries against a secure MAS, shared by the outsider processes
of the secure-profile tests (``secure_outsider.py`` for ``mas run``, ``run_outsider.py`` for ``faultmas
run``). Each attempt is a separate network message."""
from __future__ import annotations

from typing import Callable

from agents.transport import Envelope, ZenohTransport
from agents.transport.identity import Identity
from agents.transport.keys import control_key

OUTSIDER = "mallory"
EVIL_PLAN = "{+!evil <- +evil_ran.}"


def posing_as(name: str, own_key) -> Identity:
    """An identity that signs as ``name`` with the outsider's own key (a key the project does not list)."""
    return Identity({name: own_key.public_key()}, {name: own_key})


def attack_inbox(put: Callable[[bytes], None], mas: str, target: str, member: str, own_key, goal: str,
                 query: str) -> None:
    """On ``target``'s inbox: an unsigned tell, an unsigned goal under ``member``'s name, its own signed
    tell/achieve/tellHow/askOne, a tell under ``member``'s name signed with its own key."""
    def env(sender: str, performative: str, content: str) -> Envelope:
        return Envelope(mas, sender, (target,), performative, content)
    outsider = posing_as(OUTSIDER, own_key)
    put(env(OUTSIDER, "tell", "evil_unsigned").encode())                           # unsigned
    put(env(member, "achieve", goal).encode())                                     # unsigned, a member's name
    for performative, content in (("tell", "evil_signed"), ("achieve", goal), ("tellHow", EVIL_PLAN),
                                  ("askOne", query)):
        put(outsider.seal(OUTSIDER, env(OUTSIDER, performative, content).encode()))  # key not listed
    put(posing_as(member, own_key).seal(member, env(member, "tell", "evil_forged").encode()))  # own key


def attack_stop(transport: ZenohTransport, mas: str, member: str, own_key) -> None:
    """Stops on the control key: unsigned under ``member``'s name, signed by itself, claiming to be the
    launcher (without its token)."""
    session = transport.session
    session.put(control_key(mas), b'{"command":"stop","by":"%s","delay":0}' % member.encode())
    session.put(control_key(mas), posing_as(OUTSIDER, own_key).seal_control(
        {"command": "stop", "by": OUTSIDER, "delay": 0}))
    transport.publish_control("stop", by="launcher", delay=0.0)


def claim_alive(session, mas: str, names: list[str]) -> list:
    """Liveliness tokens on ``names``: a member's (to keep it alive after its death, or make it look up before it
    is), a non-member's (a fake member). Returns the tokens: up while the caller keeps them."""
    from agents.transport.keys import alive_key

    return [session.liveliness().declare_token(alive_key(mas, name)) for name in names]


def forge_heartbeats(session, mas: str, names: list[str], own_key) -> None:
    """Per name, heartbeats that prove nothing: unsigned, and signed with the outsider's own key under it."""
    from agents.transport.keys import heartbeat_key

    for name in names:
        document = b'{"agent":"%s"}' % name.encode()
        session.put(heartbeat_key(mas, name), document)                                      # unsigned
        session.put(heartbeat_key(mas, name), posing_as(name, own_key).seal(name, document))  # its own key


def forge_progress(transport: ZenohTransport, mas: str, agent: str, step: str, detail: str, own_key) -> None:
    """``.progress`` reports on the control key that ``agent`` never made: unsigned under its name, signed by
    the outsider itself, and under its name signed with the outsider's own key."""
    session = transport.session
    report = {"command": "progress", "agent": agent, "step": step, "detail": detail}
    transport.publish_control(**{**report, "by": agent})                                        # unsigned
    session.put(control_key(mas), posing_as(OUTSIDER, own_key).seal_control({**report, "by": OUTSIDER}))
    session.put(control_key(mas), posing_as(agent, own_key).seal_control({**report, "by": agent}))
