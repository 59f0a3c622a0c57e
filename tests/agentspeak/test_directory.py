"""The directory facilitator in one process, as Jason 3.3's local infrastructure (``BaseLocalMAS``,
``BaseRuntimeServices``) does it: the type is ignored, a service is its text, subscribers are told
``provider(Ag, "S")`` from ``df`` on every registration, a killed agent's registrations go, and a search
lists providers in the order of Java's ``HashSet``. Across processes: tests/agents/test_directory.py."""
from __future__ import annotations

import textwrap

from agentspeak.directory import Directory, java_string_hash, jason_set_order
from tests.agentspeak.harness import run_mas


def asl(text: str) -> str:
    return textwrap.dedent(text).strip() + "\n"


def test_search_ignores_the_type_and_a_service_is_its_text():
    out = run_mas({
        "c": asl("""
            !start.
            +!start <- .wait(100);
                .df_search("sell(book)", L1); .print(no_type(L1));
                .df_search(sell(book), "book-trading", L2); .print(with_type(L2));
                .df_search("sell(book)", "another-type", L3); .print(other_type(L3));
                .df_search("buy(book)", L4); .print(none(L4)).
        """),
        "bob": asl('!r.\n+!r <- .df_register("sell(book)", "book-trading").'),
        "alice": asl("!r.\n+!r <- .df_register(sell(book)).\n"),
    })
    # Jason's own example: "unifies L with [bob,alice] in case these two agents have registered"
    assert out == ["[c] no_type([bob,alice])", "[c] with_type([bob,alice])", "[c] other_type([bob,alice])",
                   "[c] none([])"]


def test_subscribers_are_told_on_each_registration_and_nothing_on_deregistration_or_death():
    out = run_mas({
        "c": asl("""
            !start.
            +!start <- .df_subscribe(seller).
            +provider(A, S)[source(df)] <- .print(told(A, S)); -provider(A, S)[source(df)].
            +step(2)[source(s)] <- .df_search(seller, L); .print(after_deregister(L)); .kill_agent(t);
                .df_search(seller, L2); .print(after_kill(L2)); .send(s, achieve, again).
        """),
        "s": asl("""
            !start.
            +!start <- .wait(50); .df_register(seller); .wait(50);
                .df_deregister(seller); .send(c, tell, step(2)).
            +!again <- .df_register(seller).
        """),
        "t": asl("!start.\n+!start <- .df_register(seller).\n"),
    })
    told = [line for line in out if "told" in line]
    # t registered before the subscription (told at once), s after it, and told again when s registers again
    assert told == ['[c] told(t,"seller")', '[c] told(s,"seller")', '[c] told(s,"seller")']
    assert "[c] after_deregister([t])" in out and "[c] after_kill([])" in out


def test_a_killed_agent_loses_its_registrations_and_subscriptions():
    told: list[tuple] = []
    directory = Directory(lambda *told_args: told.append(told_args))
    directory.subscribe("c", "x")
    directory.register("a", "x")
    directory.forget("c")
    directory.register("b", "x")
    directory.forget("a")
    assert told == [("c", "a", "x")] and directory.search("x") == ["b"]


def test_search_order_is_the_order_of_javas_hashset():
    # String.hashCode: well-known values, the 32-bit overflow, and a collision
    assert java_string_hash("hello") == 99162322
    assert java_string_hash("polygenelubricants") == 0x80000000  # Integer.MIN_VALUE
    assert java_string_hash("Aa") == java_string_hash("BB") == 2112
    # HashSet<String> iterates by bucket (h ^ h >>> 16) & (capacity - 1): bob (4) before alice (15)
    assert jason_set_order(["alice", "bob", "alice"]) == ["bob", "alice"]
    assert jason_set_order(["c", "a", "b"]) == ["a", "b", "c"]
    # past 12 names the table has 32 buckets: "q" (113 -> 17) comes after "b" (98 -> 2) and "a" (97 -> 1)
    names = [chr(c) for c in range(ord("a"), ord("a") + 13)] + ["q"]
    assert jason_set_order(names)[:2] == ["a", "b"] and jason_set_order(names)[-1] == "q"
