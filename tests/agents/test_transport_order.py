"""Order between what different subscribers of one process receive, over real Zenoh sessions on loopback.

zenoh-python runs each subscriber's callbacks on a thread of its own and an inbox is drained by a thread of ours,
so a process could hand things over in another order than they were sent: a ``kill`` of an agent before the
message sent to it just before (the agent layer acts on a kill in the agent's next turn, which hid it there: 0 of
60 kills of agents of another process with the code before), an agent's leave before its last message, its first message before its join,
a made agent's first message before the token saying who made it (with which an ``achieve`` from it is checked). Each test sends ``PAIRS`` pairs and counts the pairs handed over in the wrong order (before the fix,
in 4-7 runs: kills 26-103 of 200, leaves 87-137, joins 12-37 (secure profile: 23-73), made agents 7-26; after: 0;
``agents.transport.inbox_barrier``, ``config.build_config``, ``ZenohTransport._open_signed``)."""
from __future__ import annotations

import threading

import pytest

from agents.transport import Envelope, ZenohOptions, ZenohTransport
from tests.agents.transport_fixtures import poll, unique_mas

PAIRS = 200


class Log:
    """What the receiving process handed over, in its order (events come from several threads)."""

    def __init__(self) -> None:
        self.events: list[tuple[str, str]] = []
        self._lock = threading.Lock()

    def __call__(self, kind: str, name: str) -> None:
        with self._lock:
            self.events.append((kind, name))

    def inversions(self, first: str, then: str) -> int:
        """Names whose ``then`` event was handed over before their ``first`` one."""
        seen, wrong = set(), set()
        for kind, name in list(self.events):
            if kind == first:
                seen.add(name)
            elif kind == then and name not in seen:
                wrong.add(name)
        return len(wrong)


@pytest.fixture
def pair():
    """Two processes' transports of one MAS (two Zenoh sessions, linked on loopback): sender and receiver."""
    mas = unique_mas("order")
    receiver = ZenohTransport(mas).open()
    sender = ZenohTransport(mas, ZenohOptions(connect=tuple(receiver.endpoints))).open()
    try:
        yield sender, receiver
    finally:
        sender.close()
        receiver.close()


@pytest.fixture
def secure_pair():
    """``pair`` in the secure profile: the receiver holds ``b``'s key, the sender ``a``'s and ``j0``... ``j199``'s."""
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey

    from agents.transport.identity import Identity

    names = ["a", "b", *(f"j{i}" for i in range(PAIRS))]
    private = {name: Ed25519PrivateKey.generate() for name in names}
    public = {name: key.public_key() for name, key in private.items()}
    mas = unique_mas("sorder")
    receiver = ZenohTransport(mas, identity=Identity(public, {"b": private["b"]})).open()
    sender = ZenohTransport(mas, ZenohOptions(connect=tuple(receiver.endpoints)),
                            identity=Identity(public, {name: private[name] for name in names if name != "b"})).open()
    try:
        yield sender, receiver
    finally:
        sender.close()
        receiver.close()


def tell(transport: ZenohTransport, sender: str, receiver: str) -> None:
    assert transport.send(Envelope(transport.mas, sender, (receiver,), "tell", "last")) == ()


def test_a_kill_is_handed_over_after_the_message_sent_to_the_agent_before_it(pair):
    sender, receiver = pair
    log = Log()
    victims = [f"b{i}" for i in range(PAIRS)]
    for name in victims:
        receiver.register(name, lambda envelope, name=name: log("message", name))
    receiver.on_control(lambda message: message.get("command") == "kill" and log("kill", message["agent"]))
    sender.register("a", lambda envelope: None)
    assert sender.wait_for_agents(victims, timeout=30)
    for name in victims:   # as `.send(B, tell, ...); .kill_agent(B)` of an agent of another process
        tell(sender, "a", name)
        sender.publish_control("kill", agent=name, by="a")
    assert poll(lambda: len(log.events) == 2 * PAIRS, timeout=30), len(log.events)
    assert log.inversions("message", "kill") == 0


def test_an_agent_that_leaves_is_reported_gone_after_its_last_message(pair):
    sender, receiver = pair
    log = Log()
    receiver.register("b", lambda envelope: log("message", envelope.sender))
    receiver.on_presence(lambda name, alive: alive or log("gone", name))
    for i in range(PAIRS):
        name = f"d{i}"
        sender.register(name, lambda envelope: None)
        assert receiver.wait_for_agents([name], timeout=10)
        tell(sender, name, "b")
        sender.unregister(name)          # its last message, then its presence goes
    assert poll(lambda: len(log.events) == 2 * PAIRS, timeout=30), len(log.events)
    assert log.inversions("message", "gone") == 0


@pytest.mark.parametrize("profile", ["pair", "secure_pair"])
def test_a_new_agent_is_reported_alive_before_its_first_message(profile, request):
    """(In the secure profile an agent is alive once its token is up and a message signed by it came: before, the
    first was its heartbeat, handled on the heartbeat subscriber's thread, often after its first message.)"""
    sender, receiver = request.getfixturevalue(profile)
    log = Log()
    receiver.register("b", lambda envelope: log("message", envelope.sender))
    receiver.on_presence(lambda name, alive: alive and log("alive", name))
    sender.register("a", lambda envelope: None)
    assert receiver.wait_for_agents(["a"], timeout=30)
    for i in range(PAIRS):
        name = f"j{i}"
        sender.register(name, lambda envelope: None)   # its token, then at once its first message
        tell(sender, name, "b")
    assert poll(lambda: sum(kind == "message" for kind, _ in list(log.events)) == PAIRS, timeout=30), log.events
    assert log.inversions("alive", "message") == 0


def test_an_agent_made_at_run_time_is_known_as_such_before_its_first_message(pair):
    sender, receiver = pair
    creators: dict[str, str | None] = {}
    receiver.register("b", lambda envelope: creators.setdefault(envelope.sender, receiver.creator_of(envelope.sender)))
    sender.register("a", lambda envelope: None)
    assert sender.wait_for_agents(["b"], timeout=30)
    for i in range(PAIRS):   # as `.create_agent(c, "c.asl")` whose first act is `.send(b, achieve, ...)`
        sender.register(f"c{i}", lambda envelope: None, creator="a")
        tell(sender, f"c{i}", "b")
    assert poll(lambda: len(creators) == PAIRS, timeout=30), len(creators)
    unknown = [name for name, creator in creators.items() if creator != "a"]
    assert len(unknown) == 0, f"{len(unknown)} of {PAIRS} made agents not known as made: {unknown[:5]}"


LEAVER = """
!start.
+!start <- .wait(agent_alive(b)); .send(b, tell, bye); .my_name(Me); .kill_agent(Me).
"""
WATCHER = """
+bye[source(D)] <- .print(bye(D)).
-agent_alive(D) <- .print(gone(D)).
"""


def test_an_agent_perceives_another_gone_after_reading_its_last_message(pair):
    """The agent level: ``d`` tells ``b`` bye and kills itself; ``b`` prints ``bye`` and, on ``-agent_alive(d)``,
    ``gone``. A cycle runs feedback (the presence percept) before it reads a message, so even handed over in order
    the leave came first when both were there (``zenoh_arch._after_mail``). Before: 6-7 of these 20 pairs printed
    ``gone`` first, with the transport's fix alone too; 7 of 8 runs of one such pair with ``mas run --processes``."""
    from agents.zenoh_arch import TransportBridge
    from agentspeak.runtime import LocalRuntime

    sender, receiver = pair
    leavers = [f"d{i}" for i in range(20)]
    printed = Log()
    watching = LocalRuntime(printer=lambda name, text: printed(*text.rstrip(")").split("(")))
    watching.add_agent("b", WATCHER, "b.asl")
    leaving = LocalRuntime()
    for name in leavers:
        leaving.add_agent(name, LEAVER, "d.asl")
    runs = []
    for runtime, transport in ((watching, receiver), (leaving, sender)):
        bridge = TransportBridge(runtime, transport, declared=["b", *leavers]).attach()
        runs.append(threading.Thread(target=bridge.run, kwargs={"timeout": 60}, daemon=True))
    for run in runs:
        run.start()
    try:
        assert poll(lambda: len(printed.events) == 2 * len(leavers), timeout=60), printed.events
        assert printed.inversions("bye", "gone") == 0, printed.events
    finally:
        watching.stop()
        leaving.stop()
        for run in runs:
            run.join(10)
