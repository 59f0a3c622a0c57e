"""Claims on names made at run time (``agents.transport.name_claims``): of processes that claim one name at the same
moment exactly one gets it, a won claim holds the name until it is released, a process that does not answer makes
a claim fail in bounded time with a reason, and an answer that cannot be read is dropped with a log line. Real Zenoh
sessions on loopback (two in this process), the in-memory bus (the runtime's side), and the deciding rule alone with
its asks ordered step by step (the cases a race hits only now and then); the two-process run of `faultmas mas run`
is in ``tests/agents/test_runtime_agents.py``."""
from __future__ import annotations

import os
import signal
import threading
import time

import pytest

from agents.transport import LocalBus, LocalTransport, ZenohOptions, ZenohTransport
from agents.transport import keys
from agents.transport.name_claims import Claimant, NameClaims, NameUndecided, encode_claim
from agents.zenoh_arch import TransportBridge
from agentspeak.runtime import LocalRuntime
from agentspeak.stdlib.registry import IAError
from tests.agents.distributed_fixtures import write_files
from tests.agents.transport_fixtures import probe, unique_mas


@pytest.fixture
def two_processes():
    """Two Zenoh sessions of one MAS linked on loopback, each a transport as a process has."""
    mas = unique_mas("claim")
    one = ZenohTransport(mas).open()
    two = ZenohTransport(mas, ZenohOptions(connect=tuple(one.endpoints))).open()
    one.register("a", lambda envelope: None)
    two.register("b", lambda envelope: None)
    assert one.wait_for_agents(["b"], 10) and two.wait_for_agents(["a"], 10)
    yield one, two
    two.close()
    one.close()


def race(transports, name: str, creators=("a", "b")) -> list[bool | None]:
    """Each transport claims ``name`` on a thread of its own, released at the same moment (None: no decision)."""
    start, results = threading.Barrier(len(transports)), [None] * len(transports)

    def claim(i: int) -> None:
        start.wait()
        results[i] = transports[i].claim_name(name, creators[i], timeout=3.0)

    threads = [threading.Thread(target=claim, args=(i,)) for i in range(len(transports))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(30)
    return results


def test_of_two_processes_claiming_one_name_at_once_exactly_one_gets_it(two_processes):
    one, two = two_processes
    for i in range(100):
        result = race(two_processes, f"kid{i}", creators=("a", "b") if i % 2 else ("b", "a"))
        assert sorted(result, key=str) == [False, True], (i, result)
    # the winner holds the name: a later claim, from either side, loses it until the winner releases it
    winner, loser = (one, two) if one._name_claims.holds("kid0") else (two, one)
    assert not loser.claim_name("kid0", "c") and not loser.claim_name("kid0", "a")
    winner.release_name("kid0")
    assert loser.claim_name("kid0", "c")


def test_claims_made_on_many_threads_of_the_in_memory_bus_give_each_name_once(monkeypatch):
    mas, bus = unique_mas("claim"), LocalBus()
    transports = [LocalTransport(mas, bus).open() for _ in range(4)]
    for transport in transports:   # each asks a moment after it recorded its claim: the others have recorded theirs
        ask = transport._ask_claims
        monkeypatch.setattr(transport, "_ask_claims", lambda name, timeout, ask=ask: time.sleep(0.002) or ask(name, timeout))
    for i in range(30):
        result = race(transports, f"kid{i}", creators=("d", "c", "b", "a"))
        assert result.count(True) == 1, (i, result)


def scripted(tables, first_asks):
    """An ``ask`` over ``tables`` (the processes' claims) whose first ask on each thread runs ``first_asks[creator]``
    around its reading: (before, after) callables, to order the claims' steps exactly."""
    mine = threading.local()

    def ask(name: str, timeout: float) -> dict[Claimant, bool]:
        view = lambda: {claimant: won for table in tables for held, claimant, won in table.held() if held == name}
        if getattr(mine, "asked", False):
            return view()
        mine.asked = True
        before, after = first_asks[mine.creator]
        before()
        seen = view()
        after()
        return seen
    return ask, mine


def claim_on_threads(claims) -> dict[str, bool]:
    """Run ``claims`` [(table, creator, ask, mine, wait_first)] on threads; {creator: won}."""
    results = {}

    def run(table, creator, ask, mine, wait_first) -> None:
        mine.creator = creator
        wait_first()
        results[creator] = table.claim("bob", creator, ask, timeout=3.0)

    threads = [threading.Thread(target=run, args=claim) for claim in claims]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(10)
    return results


def test_claims_that_see_each_other_go_to_the_creator_that_sorts_first():
    """Both claims recorded before either is read (each sees the other's pending): the claimant that sorts first
    gets the name (it waits for the other to withdraw), the other loses at once."""
    first, second = NameClaims("p1"), NameClaims("p2")
    recorded, read = threading.Barrier(2), threading.Barrier(2)
    both = (lambda: recorded.wait(5), lambda: read.wait(5))
    ask, mine = scripted((first, second), {"amy": both, "zed": both})
    results = claim_on_threads([(second, "zed", ask, mine, lambda: None), (first, "amy", ask, mine, lambda: None)])
    assert results == {"amy": True, "zed": False}
    assert first.held() == [("bob", Claimant("amy", "p1"), True)] and second.held() == []


def test_a_claim_that_did_not_see_an_earlier_one_loses_to_it_whatever_the_names():
    """zed's claim is read before amy's is recorded (zed sees nothing: it wins, as the first would under Jason's
    lock); amy, which sorts first, then sees zed's claim pending: it must wait for zed's decision, not take the name."""
    first, second = NameClaims("p1"), NameClaims("p2")
    zed_read, amy_read = threading.Event(), threading.Event()
    nothing = lambda: None
    ask, mine = scripted((first, second), {"zed": (nothing, lambda: zed_read.set() or amy_read.wait(5)),
                                            "amy": (nothing, amy_read.set)})
    results = claim_on_threads([(second, "zed", ask, mine, nothing), (first, "amy", ask, mine, lambda: zed_read.wait(5))])
    assert results == {"amy": False, "zed": True}


def test_a_process_that_does_not_answer_makes_the_claim_fail_in_bounded_time(two_processes, tmp_path):
    """A process that stays connected but does not answer (its answer held 3 s) leaves the claim undecided: it fails
    after the timeout, withdrawn, and ``.create_agent`` fails saying why (a name nobody is asked about is free)."""
    one, _ = two_processes
    stalled = threading.Event()
    mute = one.session.declare_queryable(keys.claim_pattern(one.mas), lambda query: stalled.wait(3))
    try:
        began = time.monotonic()
        with pytest.raises(NameUndecided, match="did not answer"):
            one.claim_name("kid", "a", timeout=0.5)
        assert time.monotonic() - began < 2.5
        assert one._name_claims.held() == []
        runtime = LocalRuntime()
        bridge = TransportBridge(runtime, one).attach()
        bridge.claim_timeout = 0.5
        with pytest.raises(IAError, match="could not agree that the name is free") as failed:
            runtime.create_agent("kid", str(write_files(tmp_path, {"kid.asl": ""}) / "kid.asl"))
        assert failed.value.error == "ia_failed" and "kid" not in runtime.agents and one._name_claims.held() == []
    finally:
        stalled.set()
        mute.undeclare()


def test_an_answer_that_is_no_claim_is_dropped_with_a_log_line(two_processes, caplog):
    one, two = two_processes
    liar = one.session.declare_queryable(keys.claim_pattern(one.mas),
                                         lambda query: query.reply(keys.claim_key(one.mas, "kid"), b"{not json"))
    try:
        assert two.claim_name("kid", "b")
        assert two.dropped["bad_claim"] >= 1
        assert "bad_claim" in caplog.text
    finally:
        liar.undeclare()


def test_a_made_agent_holds_its_name_in_the_other_processes_until_it_is_killed(tmp_path, monkeypatch):
    """The runtime's side, on the in-memory bus: a name made in one process is claimed there (the other process's
    ``.create_agent`` of it gets ``kid_1`` even before it sees the agent), and free again once the agent is killed."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "kid.asl").write_text("")
    mas, bus = unique_mas("claim"), LocalBus()
    here, there = LocalRuntime(), LocalRuntime()
    transports = [LocalTransport(mas, bus).open() for _ in range(2)]
    bridges = [TransportBridge(runtime, transport).attach() for runtime, transport in zip((here, there), transports)]
    assert here.create_agent("kid", "kid.asl") == "kid"
    monkeypatch.setattr(bridges[1], "taken", lambda name: False)   # as if its presence had not arrived yet
    assert there.create_agent("kid", "kid.asl") == "kid_1"
    here.kill_agent("kid")
    assert there.create_agent("kid", "kid.asl") == "kid"
    for bridge in bridges:
        bridge.detach()
    for transport in transports:
        transport.close()


def test_a_process_that_claims_every_name_makes_create_agent_fail_not_loop(two_processes, tmp_path):
    """Every name lost is another process's, so a creator moves on; one that claims them all (a bug, or an outsider
    in the default profile, where a name is a claim) makes ``.create_agent`` fail after ``MAX_CLAIMS_LOST`` names."""
    one, _ = two_processes
    greedy = one.session.declare_queryable(keys.claim_pattern(one.mas), lambda query: query.reply(
        str(query.key_expr), encode_claim(keys.last_chunk(str(query.key_expr)), Claimant("mallory", "x"), True)))
    try:
        runtime = LocalRuntime()
        TransportBridge(runtime, one).attach()
        with pytest.raises(IAError, match=r"cannot create agent kid: 100 names in a row \(kid to kid_99\) were claimed"):
            runtime.create_agent("kid", str(write_files(tmp_path, {"kid.asl": ""}) / "kid.asl"))
        assert one._name_claims.held() == [] and not runtime.agents
    finally:
        greedy.undeclare()


def test_a_claim_is_decided_without_a_frozen_process_once_its_link_lease_ends():
    """A process frozen (SIGSTOP: its link stays open) cannot answer; Zenoh drops it when the link lease (1 s) ends and
    the claim is decided among those left, well before the claim's own timeout: the creator waits, never hangs."""
    mas = unique_mas("claim")
    with ZenohTransport(mas) as transport:
        child = probe("echo", mas, "bob", transport.endpoints)
        try:
            assert transport.wait_for_agents(["bob"], timeout=30)
            assert transport.claim_name("before", "a")   # the child answers while it runs
            os.kill(child.pid, signal.SIGSTOP)
            began = time.monotonic()
            assert transport.claim_name("kid", "a", timeout=10.0)
            assert time.monotonic() - began < 6.0
        finally:
            os.kill(child.pid, signal.SIGKILL)
            child.stop()
