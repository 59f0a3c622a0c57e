"""The wire envelope: round trip, unique ids, and one refusal reason per kind of bad input."""
from __future__ import annotations

import json

import pytest
from hypothesis import given, settings, strategies as st

from agents.transport.envelope import (DROP_REASONS, PERFORMATIVES, BadMessage, Envelope, decode,
                                       is_valid_name, new_message_id)
from agents.transport.probe import bad_payloads

names = st.from_regex(r"[A-Za-z_][A-Za-z0-9_.\-]{0,12}", fullmatch=True)


@settings(max_examples=100, deadline=None)
@given(sender=names, receivers=st.lists(names, min_size=1, max_size=4), performative=st.sampled_from(sorted(PERFORMATIVES)),
       content=st.text(max_size=200), reply=st.one_of(st.none(), st.text(min_size=1, max_size=20)))
def test_round_trip_keeps_every_field(sender, receivers, performative, content, reply):
    envelope = Envelope("mas1", sender, tuple(receivers), performative, content, in_reply_to=reply)
    assert decode(envelope.encode()) == envelope


def test_wire_form_is_compact_readable_json():
    envelope = Envelope("rescue", "alice", ("bob",), "tell", "pos(3,4)", message_id="p.1")
    assert envelope.encode() == (b'{"v":1,"id":"p.1","mas":"rescue","from":"alice","to":["bob"],'
                                 b'"perf":"tell","content":"pos(3,4)"}')


def test_message_ids_are_unique_and_carry_a_process_prefix():
    ids = {new_message_id() for _ in range(10_000)}
    assert len(ids) == 10_000
    assert len({i.split(".")[0] for i in ids}) == 1


def test_reply_goes_back_to_the_sender_and_names_the_question():
    question = Envelope("m", "alice", ("bob", "carol"), "askOne", "pos(X,Y)")
    answer = question.reply("tell", "pos(1,2)", sender="carol")
    assert (answer.sender, answer.receivers, answer.in_reply_to) == ("carol", ("alice",), question.message_id)


@pytest.mark.parametrize("reason, payload", [
    (reason, payload) for reason, payload in bad_payloads("m", "alice", "bob", 1024)
    if reason not in ("foreign_mas", "not_addressed")  # decode fine; the transport refuses them
])
def test_each_bad_payload_is_refused_with_its_reason(reason, payload):
    with pytest.raises(BadMessage) as caught:
        decode(payload, max_size=1024)
    assert caught.value.reason == reason
    assert reason in DROP_REASONS


def test_refusal_names_the_sender_when_it_can_be_read():
    payload = json.dumps({"v": 1, "id": "a.1", "mas": "m", "from": "mallory", "to": ["bob"],
                          "perf": "hack", "content": "x"}).encode()
    with pytest.raises(BadMessage) as caught:
        decode(payload)
    assert (caught.value.reason, caught.value.sender) == ("unknown_performative", "mallory")


@pytest.mark.parametrize("version", [True, 1.0, "1", 2])
def test_only_the_integer_version_is_accepted(version):
    payload = json.dumps({"v": version, "id": "a.1", "mas": "m", "from": "a", "to": ["b"],
                          "perf": "tell", "content": "x"}).encode()
    with pytest.raises(BadMessage, match="bad_version"):
        decode(payload)


def test_size_limit_is_checked_before_parsing():
    with pytest.raises(BadMessage, match="too_large"):
        decode(b"x" * 101, max_size=100)


@pytest.mark.parametrize("name, ok", [("bob", True), ("robot-1.a", True), ("a/b", False), ("*", False),
                                      ("", False), ("a b", False), ("$x", False), (3, False)])
def test_names_must_be_one_key_chunk(name, ok):
    assert is_valid_name(name) is ok


def test_building_a_bad_envelope_raises():
    with pytest.raises(BadMessage, match="unknown_performative"):
        Envelope("m", "a", ("b",), "shout", "x")
    with pytest.raises(BadMessage, match="bad_field_type"):
        Envelope("m", "a", (), "tell", "x")


@pytest.mark.parametrize("field, value", [("mas", ["m"]), ("from", {"a": 1}), ("to", [["bob"]]), ("perf", ["tell"])])
def test_unhashable_fields_are_refused_not_raised(field, value):
    data = {"v": 1, "id": "a.1", "mas": "m", "from": "alice", "to": ["bob"], "perf": "tell", "content": "x"}
    data[field] = value
    with pytest.raises(BadMessage) as caught:
        decode(json.dumps(data).encode())
    assert caught.value.reason == "bad_field_type"
