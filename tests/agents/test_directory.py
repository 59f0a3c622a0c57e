"""The directory facilitator across processes (agents.directory): ``.df_search`` finds the agents of
other processes, ``.df_subscribe`` hears of their registrations, a deregistration or a dead process is no
longer found, with the results of the in-process run; in the secure profile an outsider cannot forge a
registration. Real Zenoh sessions and ``faultmas`` processes on loopback; the in-memory bus for the
bridge's logic."""
from __future__ import annotations

import json
import signal
import time
from pathlib import Path

import zenoh

from agents.directory import NetworkDirectory
from agents.mas_cli import build_local_mas
from agents.transport import ZenohOptions, ZenohTransport, loopback_endpoint
from agents.transport import keys
from agents.transport.identity import generate_keys, project_identity
from agents.transport.local_transport import LocalBus, LocalTransport
from agents.transport.registrations import encode_services
from agents.zenoh_arch import TransportBridge
from agentspeak.mas2j import load_mas2j
from agentspeak.runtime import LocalRuntime
from tests.agents.distributed_fixtures import agent_run, mas_run, write_files
from tests.agents.transport_fixtures import poll, unique_mas

# buyer subscribes, then searches once alice, bob (with a type) and carol registered; bob deregisters;
# carol is killed (polled until gone); bob registers again, which buyer is told of again, and stops the MAS
BOOKS = {
    "buyer.asl": r'''
!start.
+!start <- .df_subscribe("sell(book)").
+provider(bob, S)[source(df)] : seen(bob) <- .print(told_again(bob, S)); .stopMAS.
+provider(A, S)[source(df)] <- +seen(A); .print(told(A, S)); -provider(A, S)[source(df)].
+ready[source(_)] : .count(ready[source(_)], 3) <-
    .df_search("sell(book)", L); .print(found(L));
    .df_search(sell(book), "book-trading", L2); .print(found_with_type(L2));
    .df_search("buy(book)", L3); .print(nobody(L3));
    .send(bob, achieve, leave).
+left[source(bob)] <- .df_search("sell(book)", L); .print(after_leave(L)); .send(carol, achieve, quit); !gone(carol).
+!gone(A) <- .df_search("sell(book)", L);
    if (.member(A, L)) { .wait(50); !gone(A) } else { .print(gone(A, L)); .send(bob, achieve, come_back) }.
''',
    "alice.asl": '!start.\n+!start <- .df_register("sell(book)"); .send(buyer, tell, ready).\n',
    "bob.asl": r'''
!start.
+!start <- .df_register(sell(book), "book-trading"); .send(buyer, tell, ready).
+!leave[source(A)] <- .df_deregister("sell(book)"); .send(A, tell, left).
+!come_back <- .df_register("sell(book)").
''',
    "carol.asl": '!start.\n+!start <- .df_register("sell(book)"); .send(buyer, tell, ready).\n+!quit <- .kill_agent(carol).\n',
    "books.mas2j": "MAS books { agents: buyer; alice; bob; carol; }\n",
}


def test_search_and_subscribe_reach_the_agents_of_other_processes_as_in_one_process(tmp_path):
    write_files(tmp_path, BOOKS)
    here: list[str] = []
    build_local_mas(load_mas2j(str(tmp_path / "books.mas2j")),
                    printer=lambda n, t: here.append(f"[{n}] {t}")).run(timeout=30)
    run = mas_run(tmp_path / "books.mas2j", "--processes", "--timeout", "60", cwd=tmp_path)
    assert run.finish() == 0, run.err[-20:]
    for out in (here, run.out):
        assert out[-1] == '[buyer] told_again(bob,"sell(book)")', out
        # the order of Java's HashSet, as Jason's search gives it; the type is ignored as in Jason
        for line in ("[buyer] found([carol,bob,alice])", "[buyer] found_with_type([carol,bob,alice])",
                     "[buyer] nobody([])", "[buyer] after_leave([carol,alice])", "[buyer] gone(carol,[alice])"):
            assert line in out, out
        assert sorted(line for line in out if "told(" in line) == [
            f'[buyer] told({name},"sell(book)")' for name in ("alice", "bob", "carol")]
    # the same lines; across processes a provider is told asynchronously, so only their order may differ
    assert sorted(run.out) == sorted(here)


def test_a_dead_process_registrations_vanish_and_subscribers_hear_of_new_ones(tmp_path):
    """A provider in a ``faultmas agent run`` process, SIGKILLed: no goodbye, only its session gone."""
    write_files(tmp_path, {"seller.asl": '!start.\n+!start <- .df_register("sell(book)"); .print(registered).\n'})
    mas = unique_mas("df")
    heard: list[str] = []
    with ZenohTransport(mas, ZenohOptions(listen=(loopback_endpoint(),))) as here:
        here.watch_registrations("sell(book)", heard.append)
        seller = agent_run(tmp_path, "seller", mas, here.endpoints[0])
        try:
            assert seller.wait_out("[seller] registered", 60), seller.err[-20:]
            assert poll(lambda: heard == ["seller"], 20)
            assert here.remote_registrations() == {"seller": ["sell(book)"]}
            seller.process.kill()
            assert poll(lambda: "seller" not in here.remote_registrations(0.5), 20)
        finally:
            seller.stop(signal.SIGKILL)


def test_bridged_runtimes_share_one_directory_on_the_in_memory_bus():
    """Two 'processes' (runtimes with their transports on one bus): the same back-end the Zenoh run uses."""
    mas, bus = unique_mas(), LocalBus()
    outputs: list[str] = []
    runtimes = []
    for agents in ({"a": '!s.\n+!s <- .df_register(x).\n'},
                   {"b": '!s.\n+!s <- .df_subscribe(x).\n+provider(A, S)[source(df)] <- .print(told(A, S)).\n'}):
        runtime = LocalRuntime(printer=lambda n, t: outputs.append(f"[{n}] {t}"))
        for name, source in agents.items():
            runtime.add_agent(name, source)
        transport = LocalTransport(mas, bus).open()
        TransportBridge(runtime, transport).attach()
        runtimes.append((runtime, transport))
    (first, first_transport), (second, second_transport) = runtimes
    assert isinstance(first.directory, NetworkDirectory)
    first.run(timeout=2)
    second.run(timeout=2)
    assert outputs == ['[b] told(a,"x")']
    assert second.directory.search("x") == ["a"]
    first.directory.deregister("a", "x")
    assert second.directory.search("x") == []
    first.directory.register("a", "x")
    first_transport.unregister("a")  # its process leaves the MAS
    assert second.directory.search("x") == []


def test_an_outsider_cannot_forge_a_registration_in_the_secure_profile(tmp_path):
    mas = unique_mas("sdf")
    generate_keys(tmp_path / "keys", ["alice", "bob"])
    generate_keys(tmp_path / "outside", ["mallory"])
    (tmp_path / "p.mas2j").write_text(f'MAS {mas} {{ agents: alice [key="keys"]; bob [key="keys"]; }}\n')
    project = load_mas2j(str(tmp_path / "p.mas2j"))
    endpoint = loopback_endpoint()
    alice_side = ZenohTransport(mas, ZenohOptions(listen=(endpoint,)), identity=project_identity(project, ["alice"]))
    bob_side = ZenohTransport(mas, ZenohOptions(connect=(endpoint,)), identity=project_identity(project, ["bob"]))
    outsider = zenoh.open(_client_config(endpoint))
    try:
        alice_side.open()
        bob_side.open()
        bob_side.register("bob", lambda envelope: None)
        bob_side.registrations = lambda: {"bob": ["sell(book)"]}
        bob_side.provide("bob", "sell(book)")
        heard: list[str] = []
        alice_side.watch_registrations("sell(book)", heard.append)
        alice_side.watch_registrations("buy(book)", heard.append)
        assert poll(lambda: heard == ["bob"], 20)
        # mallory answers directory queries as bob, without bob's key, and with an answer of bob's to
        # another query; then announces bob as a buyer (a token is a hint: bob's process does not confirm it)
        replayed = bob_side.identity.seal("bob", json.dumps(
            {"mas": mas, "agent": "bob", "services": ["buy(book)"], "nonce": "old"}, separators=(",", ":")).encode())

        def answer(query):
            nonce = query.payload.to_bytes().decode()
            query.reply(keys.df_key(mas, "bob"), encode_services(mas, "bob", ["buy(book)"], nonce))
            query.reply(keys.df_key(mas, "bob"), replayed)
        forger = outsider.declare_queryable(keys.df_pattern(mas), answer)
        dropped = alice_side.dropped
        assert poll(lambda: alice_side.remote_registrations(1.0) == {"bob": ["sell(book)"]}
                    and dropped["unsigned"] >= 1 and dropped["replayed"] >= 1, 20), dict(dropped)
        before = dropped["unsigned"]
        token = outsider.liveliness().declare_token(keys.provides_key(mas, "bob", "buy(book)"))
        assert poll(lambda: dropped["unsigned"] > before, 20)  # alice's process asked bob's to confirm
        time.sleep(0.5)  # the confirmation's verdict comes right after its answers
        assert heard == ["bob"]  # and was not told of the forged buy(book)
        forger.undeclare()
        token.undeclare()
    finally:
        outsider.close()
        bob_side.close()
        alice_side.close()


def _client_config(endpoint: str) -> zenoh.Config:
    from agents.transport.config import build_config
    return build_config(ZenohOptions(connect=(endpoint,)))
