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



def capture_one(session, key: str, timeout: float = 30.0) -> bytes | None:
    """The payload of the next sample put on ``key`` (None after ``timeout`` seconds)."""
    import queue

    got: queue.Queue = queue.Queue()
    subscriber = session.declare_subscriber(key, lambda sample: got.put(sample.payload.to_bytes()))
    try:
        return got.get(timeout=timeout)
    except queue.Empty:
        return None
    finally:
        subscriber.undeclare()


def forge_percepts(session, mas: str, robot: str, other: str, own_key) -> None:
    """On ``robot``'s percept key, percepts its robot never had (both wheel motors overloaded, a bumper pressed,
    kept for ever under a source of the outsider's own): unsigned, signed with the outsider's key as the
    environment, and a snapshot the environment really signed for ``other`` put again on ``robot``'s key; on the
    clock key, a time far ahead (unsigned: every deadline of the agents would pass at once)."""
    from agents.transport.identity import ENVIRONMENT
    from robot_bridge.zenoh_bridge import clock_key, robot_key

    document = (b'{"agent_name":"%s","source":"mallory","literals":["over_current(left)","over_current(right)",'
                b'"bumper(centre)"]}' % robot.encode())
    key = robot_key(mas, robot, "percepts")
    session.put(key, document)                                                         # unsigned
    session.put(key, posing_as(ENVIRONMENT, own_key).seal(ENVIRONMENT, document))      # its own key
    captured = capture_one(session, robot_key(mas, other, "percepts"))
    assert captured is not None, f"no percepts of {other} to capture"
    session.put(key, captured)                                                         # another robot's
    session.put(clock_key(mas), b"100000.0")                                           # the clock, unsigned


def forge_actions(session, mas: str, robots: list[str], own_key) -> None:
    """On each robot's action key, a turn its agent never asked for: unsigned, and signed with the outsider's
    key as the robot's agent."""
    from robot_bridge.zenoh_bridge import robot_key

    for robot in robots:
        document = b'{"agent_name":"%s","action_name":"turn","parameters":["170"],"id":990001}' % robot.encode()
        session.put(robot_key(mas, robot, "actions"), document)                        # unsigned
        session.put(robot_key(mas, robot, "actions"), posing_as(robot, own_key).seal(robot, document))


class StatusForger:
    """Answers the first action ``robot``'s agent asks for with a failure, before the robot does: unsigned, and
    signed with the outsider's key as the environment. Start it before the robot's agent starts."""

    def __init__(self, session, mas: str, robot: str, own_key) -> None:
        import re
        import threading

        from agents.transport.identity import ENVIRONMENT
        from robot_bridge.zenoh_bridge import robot_key

        self.done = threading.Event()
        status_key = robot_key(mas, robot, "status")
        forger = posing_as(ENVIRONMENT, own_key)

        def on_request(sample) -> None:
            found = re.search(rb'"id":(\d+)', sample.payload.to_bytes())
            if self.done.is_set() or found is None or int(found.group(1)) >= 990000:
                return
            self.done.set()
            document = b'{"agent_name":"%s","id":%s,"result":false,"reason":"blocked"}' % (robot.encode(),
                                                                                           found.group(1))
            session.put(status_key, document)                                          # unsigned
            session.put(status_key, forger.seal(ENVIRONMENT, document))                # its own key
        self.subscriber = session.declare_subscriber(robot_key(mas, robot, "actions"), on_request)


def forge_minds(session, mas: str, agent: str, own_key):
    """A queryable on ``agent``'s inspector state key that answers the first query it gets with a mind the agent
    never had (an evil intention, 424,242 cycles): unsigned, and signed with the outsider's key as the agent.
    Returns the queryable (it answers while the caller keeps it)."""
    import json
    import threading

    from agents.inspector.keys import state_key

    answered = threading.Event()
    mind = {"agent": agent, "cycles": 424242, "paused": False, "top": "evil_intention", "intentions": 1}
    document = json.dumps(mind, separators=(",", ":")).encode()

    def answer(query) -> None:
        if not answered.is_set():
            answered.set()
            query.reply(state_key(mas, agent), document)                                          # unsigned
            query.reply(state_key(mas, agent), posing_as(agent, own_key).seal(agent, document))   # its own key
    return session.declare_queryable(state_key(mas, agent), answer)


def forge_pause(session, mas: str, agent: str, own_key) -> list[bytes]:
    """On ``agent``'s inspector control key: a ``pause`` unsigned, and a ``step`` signed with the outsider's key
    as the agent itself. Returns the answers."""
    import json

    from agents.inspector.keys import control_key as inspect_control_key

    key = inspect_control_key(mas, agent)
    answers = []
    for payload in (json.dumps({"command": "pause"}).encode(),
                    posing_as(agent, own_key).seal_control({"command": "step", "by": agent})):
        answers += [reply.ok.payload.to_bytes() for reply in session.get(key, payload=payload, timeout=10.0)
                    if reply.ok is not None]
    return answers


def claim_subscriptions(session, mas: str, member: str, service: str) -> list:
    """``.df_subscribe`` tokens nobody proves: ``member``'s to a service it never subscribed to, and the outsider's
    own. Returns the tokens: up while the caller keeps them."""
    from agents.transport.keys import subscribes_key

    return [session.liveliness().declare_token(subscribes_key(mas, name, service)) for name in (member, OUTSIDER)]


def forge_subscription_queries(session, mas: str, member: str, service: str, own_key) -> None:
    """Directory queries saying that ``member`` subscribes to ``service``: unsigned, and signed with the
    outsider's key as ``member`` (each process that answers would remember it and tell ``member`` of providers)."""
    import json

    from agents.transport.keys import df_pattern

    request = json.dumps({"nonce": "0123456789ab", "subscribe": [member, service]}, separators=(",", ":")).encode()
    for payload in (request, posing_as(member, own_key).seal(member, request)):
        list(session.get(df_pattern(mas), payload=payload, timeout=3.0))
