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
