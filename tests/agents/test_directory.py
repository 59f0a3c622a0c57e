"""The directory facilitator across processes (agents.directory): ``.df_search`` finds the agents of
other processes, ``.df_subscribe`` hears of their registrations, a deregistration or a dead process is no
longer found, with the results of the in-process run; in the secure profile an outsider cannot forge a
registration. Real Zenoh sessions and ``faultmas`` processes on loopback; the in-memory bus for the
bridge's logic."""
from __future__ import annotations

import json
import signal

import zenoh

from agents.directory import PROVIDER_NOTICE, NetworkDirectory
from agents.mas_cli import build_local_mas
from agents.transport import Envelope, ZenohOptions, ZenohTransport, keys, loopback_endpoint
from agents.transport.config import build_config
from agents.transport.identity import generate_keys, project_identity
from agents.transport.local_transport import LocalBus, LocalTransport
from agents.transport.registrations import encode_services
from agents.zenoh_arch import TransportBridge
from agentspeak.mas2j import load_mas2j
from agentspeak.runtime import LocalRuntime
from tests.agents.distributed_fixtures import agent_run, mas_run, write_files
from tests.agents.transport_fixtures import poll, unique_mas

# buyer subscribes, then asks alice, bob (with a type) and carol to register: each is told to buyer before
# its `ready` (as Jason's DF puts it in the mailbox at once); buyer searches; bob deregisters; carol is
# killed (polled until gone); bob registers again, which buyer is told of again, and stops the MAS
BOOKS = {
    "buyer.asl": r'''
!start.
+!start <- .df_subscribe("sell(book)"); .send([alice, bob, carol], achieve, start).
+provider(bob, S)[source(df)] : seen(bob) <- .print(told_again(bob, S)); .stopMAS.
+provider(A, S)[source(df)] <- .print(told(A, S)); +seen(A); -provider(A, S)[source(df)].
+ready[source(_)] : .count(ready[source(_)], 3) <-
    .df_search("sell(book)", L); .print(found(L));
    .df_search(sell(book), "book-trading", L2); .print(found_with_type(L2));
    .df_search("buy(book)", L3); .print(nobody(L3));
    .send(bob, achieve, leave).
+left[source(bob)] <- .df_search("sell(book)", L); .print(after_leave(L)); .send(carol, achieve, quit); !gone(carol).
+!gone(A) <- .df_search("sell(book)", L);
    if (.member(A, L)) { .wait(50); !gone(A) } else { .print(gone(A, L)); .send(bob, achieve, come_back) }.
''',
    "alice.asl": '+!start[source(B)] <- .df_register("sell(book)"); .send(B, tell, ready).\n',
    "bob.asl": r'''
+!start[source(B)] <- .df_register(sell(book), "book-trading"); .send(B, tell, ready).
+!leave[source(A)] <- .df_deregister("sell(book)"); .send(A, tell, left).
+!come_back <- .df_register("sell(book)").
''',
    "carol.asl": '+!start[source(B)] <- .df_register("sell(book)"); .send(B, tell, ready).\n+!quit <- .kill_agent(carol).\n',
    "books.mas2j": "MAS books { agents: buyer; alice; bob; carol; }\n",
}


def _assert_books(out: list[str]) -> None:
    # each seller is told before its `ready` (so before the search); the sellers answer in any order
    assert sorted(out[:3]) == [f'[buyer] told({name},"sell(book)")' for name in ("alice", "bob", "carol")], out
    # the order of Java's HashSet, as Jason's search gives it; the type is ignored as in Jason
    assert out[3:] == ["[buyer] found([carol,bob,alice])", "[buyer] found_with_type([carol,bob,alice])",
                       "[buyer] nobody([])", "[buyer] after_leave([carol,alice])", "[buyer] gone(carol,[alice])",
                       '[buyer] told_again(bob,"sell(book)")'], out


def test_search_and_subscribe_reach_the_agents_of_other_processes_as_in_one_process(tmp_path):
    write_files(tmp_path, BOOKS)
    here: list[str] = []
    build_local_mas(load_mas2j(str(tmp_path / "books.mas2j")),
                    printer=lambda n, t: here.append(f"[{n}] {t}")).run(timeout=30)
    _assert_books(here)
    run = mas_run(tmp_path / "books.mas2j", "--processes", "--timeout", "60", cwd=tmp_path)
    assert run.finish() == 0, run.err[-20:]
    _assert_books(run.out)


def test_the_same_in_the_secure_profile(tmp_path):
    """Every agent's key listed: answers and provider notices are signed by their agents and checked."""
    write_files(tmp_path, {**BOOKS, "books.mas2j": 'MAS books { agents: buyer [key="keys"]; alice [key="keys"]; '
                                                   'bob [key="keys"]; carol [key="keys"]; }\n'})
    generate_keys(tmp_path / "keys", ["buyer", "alice", "bob", "carol"])
    run = mas_run(tmp_path / "books.mas2j", "--processes", "--timeout", "60", cwd=tmp_path)
    assert run.finish() == 0, run.err[-20:]
    _assert_books(run.out)
    assert not [line for line in run.err if "dropped" in line], run.err[-20:]


def test_a_dead_process_registrations_and_subscriptions_vanish(tmp_path):
    """A provider and a subscriber in ``faultmas agent run`` processes, SIGKILLed: no goodbye, only their
    sessions gone."""
    write_files(tmp_path, {"seller.asl": '!start.\n+!start <- .df_register("sell(book)"); .print(registered).\n',
                           "buyer.asl": '!start.\n+!start <- .df_subscribe("sell(book)"); .print(subscribed).\n'})
    mas = unique_mas("df")
    subscriptions: list[tuple] = []
    with ZenohTransport(mas, ZenohOptions(listen=(loopback_endpoint(),))) as here:
        here.on_subscription(lambda *change: subscriptions.append(change))
        seller = agent_run(tmp_path, "seller", mas, here.endpoints[0])
        buyer = agent_run(tmp_path, "buyer", mas, here.endpoints[0])
        try:
            assert seller.wait_out("[seller] registered", 60), seller.err[-20:]
            assert buyer.wait_out("[buyer] subscribed", 60), buyer.err[-20:]
            assert here.remote_registrations() == {"seller": ["sell(book)"]}
            assert poll(lambda: subscriptions == [("buyer", "sell(book)", True)], 20), subscriptions
            seller.process.kill()
            buyer.process.kill()
            assert poll(lambda: "seller" not in here.remote_registrations(0.5), 20)
            assert poll(lambda: subscriptions[-1:] == [("buyer", "sell(book)", False)], 20), subscriptions
        finally:
            seller.stop(signal.SIGKILL)
            buyer.stop(signal.SIGKILL)


def test_bridged_runtimes_share_one_directory_and_refuse_false_notices():
    """Two 'processes' (runtimes with their transports on one in-memory bus): the back-end the Zenoh run
    uses; a notice that is not about its sender, or to an agent that did not subscribe, is refused."""
    mas, bus = unique_mas(), LocalBus()
    outputs: list[str] = []
    runtimes = []
    for agents in ({"a": "!s.\n+!s <- .df_register(x); .send(b, tell, after).\n"},
                   {"b": "!s.\n+!s <- .df_subscribe(x).\n+provider(A, S)[source(df)] <- .print(told(A, S)).\n"
                         "+after <- .print(after).\n+provider(A, S)[source(Other)] <- .print(forged(Other))."}):
        runtime = LocalRuntime(printer=lambda n, t: outputs.append(f"[{n}] {t}"))
        for name, source in agents.items():
            runtime.add_agent(name, source)
        transport = LocalTransport(mas, bus).open()
        TransportBridge(runtime, transport).attach()
        runtimes.append((runtime, transport))
    (first, first_transport), (second, second_transport) = runtimes
    assert isinstance(first.directory, NetworkDirectory)
    second.run(timeout=1)  # b subscribes (nobody provides x yet) ...
    first.run(timeout=1)   # ... then a registers: b is told before a's next message
    second.run(timeout=1)
    assert outputs == ['[b] told(a,"x")', "[b] after"]
    assert second.directory.search("x") == ["a"]
    first.directory.deregister("a", "x")
    assert second.directory.search("x") == []
    for content in ('provider(a,"y")', 'provider(c,"x")', "provider(a,x)"):  # not subscribed, not a's, no string
        first_transport.send(Envelope(mas, "a", ("b",), "tell", content, in_reply_to=PROVIDER_NOTICE))
    assert (second_transport.dropped["not_subscribed"], second_transport.dropped["bad_df_notice"]) == (1, 2)
    second.run(timeout=1)
    assert outputs == ['[b] told(a,"x")', "[b] after"]
    first.directory.register("a", "x")
    first_transport.unregister("a")  # its process leaves the MAS
    assert second.directory.search("x") == []


def _secure_pair_and_outsider(tmp_path, mas: str):
    """alice's and bob's transports in the secure profile (keys listed in a project), and an outsider's plain
    Zenoh session on the same loopback endpoint; none of them opened yet."""
    generate_keys(tmp_path / "keys", ["alice", "bob"])
    (tmp_path / "p.mas2j").write_text(f'MAS {mas} {{ agents: alice [key="keys"]; bob [key="keys"]; }}\n')
    project = load_mas2j(str(tmp_path / "p.mas2j"))
    endpoint = loopback_endpoint()
    alice_side = ZenohTransport(mas, ZenohOptions(listen=(endpoint,)), identity=project_identity(project, ["alice"]))
    bob_side = ZenohTransport(mas, ZenohOptions(connect=(endpoint,)), identity=project_identity(project, ["bob"]))
    outsider = zenoh.open(build_config(ZenohOptions(connect=(endpoint,))))
    return alice_side, bob_side, outsider


def test_an_outsider_cannot_answer_for_an_agent_in_the_secure_profile(tmp_path):
    mas = unique_mas("sdf")
    alice_side, bob_side, outsider = _secure_pair_and_outsider(tmp_path, mas)
    try:
        alice_side.open()
        bob_side.open()
        bob_side.register("bob", lambda envelope: None)
        bob_side.registrations = lambda subscribed: {"bob": ["sell(book)"]}
        # mallory answers directory queries as bob without bob's key, and with an answer of bob's to another query
        replayed = bob_side.identity.seal("bob", json.dumps(
            {"mas": mas, "agent": "bob", "services": ["buy(book)"], "nonce": "old"}, separators=(",", ":")).encode())

        def answer(query):
            nonce = json.loads(query.payload.to_bytes())["nonce"]
            query.reply(keys.df_key(mas, "bob"), encode_services(mas, "bob", ["buy(book)"], nonce))
            query.reply(keys.df_key(mas, "bob"), replayed)
        forger = outsider.declare_queryable(keys.df_pattern(mas), answer)
        dropped = alice_side.dropped
        assert poll(lambda: alice_side.remote_registrations(1.0) == {"bob": ["sell(book)"]}
                    and dropped["unsigned"] >= 1 and dropped["replayed"] >= 1, 20), dict(dropped)
        forger.undeclare()
    finally:
        outsider.close()
        bob_side.close()
        alice_side.close()


def test_in_the_secure_profile_a_subscription_token_counts_only_while_its_agents_heartbeats_list_it(tmp_path):
    """A process that starts after a subscription hears of it from its token, proved by the subscriber's signed
    heartbeats; an outsider's token on the same member's name for another service is refused with a log line
    and never reported (before: every token was a subscription). (A run against an outsider process:
    tests/hardening/test_run_secure_outsider.py.)"""
    mas = unique_mas("sdt")
    alice_side, bob_side, outsider = _secure_pair_and_outsider(tmp_path, mas)
    seen: list = []
    try:
        alice_side.open()
        alice_side.register("alice", lambda envelope: None)
        alice_side.announce_subscription("alice", "sell(book)")
        forged = outsider.liveliness().declare_token(keys.subscribes_key(mas, "alice", "buy(car)"))
        bob_side.open()   # later: it learns of alice's subscription from her token and her heartbeats
        bob_side.register("bob", lambda envelope: None)
        bob_side.on_subscription(lambda agent, service, present: seen.append((agent, service, present)))
        assert poll(lambda: ("alice", "sell(book)", True) in seen and bob_side.dropped["unsigned"] == 1, 15), \
            (seen, dict(bob_side.dropped))
        alice_side.withdraw_subscription("alice", "sell(book)")
        assert poll(lambda: ("alice", "sell(book)", False) in seen, 15), seen
        assert all(service != "buy(car)" for _, service, _ in seen)
        forged.undeclare()
    finally:
        outsider.close()
        bob_side.close()
        alice_side.close()
