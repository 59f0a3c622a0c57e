"""The in-memory transport (the supported test double) and the logic every transport shares:
delivery and FIFO order, drops, presence, control, status/quiescence, trust."""
from __future__ import annotations

import logging

import pytest

from agents.transport import (AgentStatus, Envelope, Inbox, LocalBus, LocalTransport, TrustPolicy,
                              quiescent)
from agents.transport.probe import bad_payloads


@pytest.fixture
def two_processes():
    """Two transports on one bus, as two processes of MAS 'm' would be."""
    bus = LocalBus()
    with LocalTransport("m", bus, wire=True, max_message_size=1024) as one, \
            LocalTransport("m", bus, wire=True, max_message_size=1024) as two:
        yield one, two


def test_messages_arrive_in_order_across_and_within_transports(two_processes):
    one, two = two_processes
    alice, bob, carol = Inbox(), Inbox(), Inbox()
    one.register("alice", alice)
    one.register("carol", carol)
    two.register("bob", bob)
    for i in range(50):
        assert one.send(Envelope("m", "alice", ("bob", "carol"), "tell", f"n({i})")) == ()
    assert [e.content for e in bob.drain()] == [f"n({i})" for i in range(50)]
    assert [e.content for e in carol.drain()] == [f"n({i})" for i in range(50)]
    assert one.sent["alice"] == 100 and two.received["bob"] == 50 and one.received["carol"] == 50


def test_unknown_receivers_are_reported_not_counted(two_processes):
    one, _ = two_processes
    one.register("alice", Inbox())
    assert one.send(Envelope("m", "alice", ("nobody", "alice"), "tell", "x")) == ("nobody",)
    assert one.sent["alice"] == 1


def test_sending_for_another_mas_is_a_programming_error(two_processes):
    one, _ = two_processes
    with pytest.raises(ValueError, match="MAS 'other'"):
        one.send(Envelope("other", "a", ("b",), "tell", "x"))


def test_registering_a_name_twice_in_one_process_is_refused(two_processes):
    one, _ = two_processes
    one.register("alice", Inbox())
    with pytest.raises(ValueError, match="already registered"):
        one.register("alice", Inbox())
    with pytest.raises(ValueError, match="invalid agent name"):
        one.register("a/b", Inbox())


def test_every_bad_payload_is_dropped_logged_and_counted(two_processes, caplog):
    one, two = two_processes
    bob = Inbox()
    two.register("bob", bob)
    payloads = bad_payloads("m", "mallory", "bob", 1024)
    with caplog.at_level(logging.WARNING, logger="faultmas.transport"):
        for _, payload in payloads:
            one.put_raw("bob", payload)
        one.send(Envelope("m", "alice", ("bob",), "tell", "still_fine"))
    expected = {}
    for reason, _ in payloads:
        expected[reason] = expected.get(reason, 0) + 1
    assert dict(two.dropped) == expected
    assert len(caplog.records) == len(payloads)
    assert all("faultmas/" not in r.getMessage() and "bob" in r.getMessage() for r in caplog.records)
    assert [e.content for e in bob.drain()] == ["still_fine"]


def test_a_failing_agent_callback_does_not_break_the_sender(two_processes, caplog):
    one, two = two_processes
    two.register("bob", lambda envelope: 1 / 0)
    with caplog.at_level(logging.ERROR, logger="faultmas.transport"):
        assert one.send(Envelope("m", "alice", ("bob",), "tell", "x")) == ()
    assert "ZeroDivisionError" in caplog.text


def test_presence_is_reported_once_per_change_and_replayed_to_late_subscribers(two_processes):
    one, two = two_processes
    seen = []
    one.on_presence(lambda agent, alive: seen.append((agent, alive)))
    two.register("bob", Inbox())
    two._presence.update("bob", True)  # a join seen twice (token + history)
    late = []
    two.on_presence(lambda agent, alive: late.append((agent, alive)))
    two.unregister("bob")
    assert seen == [("bob", True), ("bob", False)]
    assert late == [("bob", True), ("bob", False)]
    assert one.wait_for_agents(["bob"], timeout=0.01, alive=False)


def test_control_reaches_every_transport_of_the_mas_only():
    bus = LocalBus()
    with LocalTransport("m", bus) as one, LocalTransport("m", bus) as two, LocalTransport("n", bus) as other:
        got = {name: [] for name in ("one", "two", "other")}
        for name, transport in (("one", one), ("two", two), ("other", other)):
            transport.on_control(got[name].append)
        one.publish_control("stop", by="alice")
    assert got == {"one": [{"command": "stop", "by": "alice"}], "two": [{"command": "stop", "by": "alice"}],
                   "other": []}


def test_status_counters_tell_when_nothing_is_in_flight(two_processes):
    one, two = two_processes
    bob = Inbox()
    one.register("alice", Inbox())
    two.register("bob", bob)
    published = []
    one.on_status(published.append)
    one.send(Envelope("m", "alice", ("bob",), "tell", "x"))
    one.publish_status("alice", busy=False)
    statuses = one.collect_status()
    assert statuses == [AgentStatus("alice", False, 1, 0), AgentStatus("bob", False, 0, 1)]
    assert quiescent(statuses)
    assert published == [AgentStatus("alice", False, 1, 0)]
    two.publish_status("bob", busy=True)
    assert not quiescent(one.collect_status())
    assert not quiescent([AgentStatus("alice", False, 2, 0), AgentStatus("bob", False, 0, 1)])


def test_status_decoding_refuses_what_is_not_a_status():
    status = AgentStatus("a", True, 3, 4)
    assert AgentStatus.decode(status.encode()) == status
    for bad in (b"[]", b'{"agent":"a","busy":1,"sent":0,"received":0}', b'{"agent":"a/b","busy":true}'):
        with pytest.raises(ValueError):
            AgentStatus.decode(bad)


def test_trust_accepts_code_only_from_declared_or_allowed_senders():
    policy = TrustPolicy("m", declared_agents={"alice", "bob"})
    plan = lambda sender: Envelope("m", sender, ("bob",), "tellHow", "+!g <- .print(hi).")  # noqa: E731
    assert policy.refusal(plan("alice")) is None
    assert policy.refusal(plan("joiner")) == "untrusted_code"
    assert policy.refusal(Envelope("m", "joiner", ("bob",), "tell", "x")) is None
    assert policy.refusal(Envelope("other", "alice", ("bob",), "tell", "x")) == "foreign_mas"
    policy.allow(["joiner"])
    assert policy.refusal(plan("joiner")) is None
    strict = TrustPolicy("m", extra_check=lambda envelope: envelope.performative != "signal")
    assert strict.refusal(Envelope("m", "a", ("b",), "signal", "x")) == "refused_by_policy"


def test_the_agent_layer_reports_its_own_refusals_the_same_way(two_processes, caplog):
    one, _ = two_processes
    envelope = Envelope("m", "joiner", ("bob",), "tellHow", "+!g <- .print(hi).")
    with caplog.at_level(logging.WARNING, logger="faultmas.transport"):
        one.report_drop(envelope, "bob", "untrusted_code", "joiner is not declared in the project")
    assert one.dropped["untrusted_code"] == 1
    assert caplog.messages == ["dropped message on agent bob from joiner: untrusted_code "
                               "(joiner is not declared in the project)"]
