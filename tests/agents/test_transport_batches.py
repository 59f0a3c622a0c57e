"""Batches: what one thread sends in a burst to another process goes out as one payload (the envelopes
one per line) and arrives as if sent one by one: same order, same checks, one drop per bad line.
Also the encoder's fast path for long contents (it must write exactly what ``json`` writes)."""
from __future__ import annotations

import json
import threading

import pytest
from hypothesis import given, settings, strategies as st

from agents.transport import Envelope, Inbox, LocalBus, LocalTransport
from agents.transport.envelope import (BATCH_BYTES, _quote, _quote_content, decode, make_envelope,
                                       split_batch)
from agents.transport.outbox import Outbox
from tests.agents.transport_fixtures import poll


class Recorder:
    """An agent's callbacks: the envelopes, and the size of each group handed over together."""

    def __init__(self) -> None:
        self.envelopes: list[Envelope] = []
        self.groups: list[int] = []
        self._since = 0

    def __call__(self, envelope: Envelope) -> None:
        self.envelopes.append(envelope)

    def delivered(self) -> None:
        self.groups.append(len(self.envelopes) - self._since)
        self._since = len(self.envelopes)

    def contents(self) -> list[str]:
        return [e.content for e in self.envelopes]


@pytest.fixture
def pair():
    """Transport ``one`` (agent alice) and ``two`` (agent bob, recorded), on the wire, as two processes."""
    bus = LocalBus()
    with LocalTransport("m", bus, wire=True, max_message_size=1024) as one, \
            LocalTransport("m", bus, wire=True, max_message_size=1024) as two:
        one.register("alice", Inbox())
        one._outbox.max_delay = 600  # only what a test does sends a batch (the late flush has its own test)
        bob, carol = Recorder(), Recorder()
        two.register("bob", bob, bob.delivered)
        two.register("carol", carol, carol.delivered)
        one.carol = carol
        yield one, two, bob


def tell(transport: LocalTransport, content: str, performative: str = "tell", **fields) -> None:
    assert transport.send(Envelope("m", "alice", ("bob",), performative, content, **fields)) == ()


def test_a_burst_goes_out_as_one_batch_in_order_when_flushed(pair):
    one, two, bob = pair
    with one.batching():
        for i in range(100):
            tell(one, f"n({i})")
        assert bob.envelopes == []  # held until flushed
        one.flush()
        assert bob.contents() == [f"n({i})" for i in range(100)]
    assert bob.groups == [100]  # one payload, one wake of the agent
    assert two.received["bob"] == 100


def test_leaving_the_batching_block_flushes_and_other_threads_send_at_once(pair):
    one, two, bob = pair
    with one.batching():
        tell(one, "held")
        thread = threading.Thread(target=tell, args=(one, "from another thread"))
        thread.start()
        thread.join()
        assert bob.contents() == ["from another thread"]
    assert bob.contents() == ["from another thread", "held"]


def test_questions_and_answers_go_at_once_after_what_was_held_before_them(pair):
    one, two, bob = pair
    with one.batching():
        tell(one, "first")
        tell(one, "q(X)", performative="askOne")
        assert bob.contents() == ["first", "q(X)"]
        tell(one, "second")
        tell(one, "answer", in_reply_to="x.1")
        assert bob.contents() == ["first", "q(X)", "second", "answer"]
        assert one.send(Envelope("m", "alice", ("carol",), "tell", "to carol")) == ()
        tell(one, "q(Y)", performative="askAll")  # what was held for carol goes first too
        assert one.carol.contents() == ["to carol"]


def test_a_batch_is_sent_when_full_and_a_big_message_goes_alone(pair):
    one, two, bob = pair
    outbox = one._outbox
    outbox.max_messages = 10
    with one.batching():
        for i in range(25):
            tell(one, f"n({i})")
        assert bob.groups == [10, 10]
        tell(one, "x" * 900)  # under the 1 KB limit, but more than the batch budget allows now
        outbox.max_bytes = 500
        tell(one, "y" * 600)
        assert bob.contents()[-1] == "y" * 600
    assert bob.contents() == [f"n({i})" for i in range(25)] + ["x" * 900, "y" * 600]


def test_what_nobody_flushes_goes_out_within_the_delay():
    sent: list[bytes] = []
    outbox = Outbox(max_delay=0.001)
    try:
        outbox.hold("bob", b"{}", sent.append)
        assert poll(lambda: sent == [b"{}"], timeout=10)
        outbox.hold("bob", b"{1}", sent.append)  # the timer thread is armed again
        outbox.hold("bob", b"{2}", sent.append)
        assert poll(lambda: sent == [b"{}", b"{1}\n{2}"], timeout=10)
    finally:
        outbox.close()


def test_each_line_of_a_batch_is_checked_alone(pair, caplog):
    one, two, bob = pair
    good = [Envelope("m", "alice", ("bob",), "tell", f"n({i})").encode() for i in range(3)]
    foreign = Envelope("other", "alice", ("bob",), "tell", "x").encode()
    batch = b"\n".join([good[0], b"{not json", foreign, b"z" * 2000, good[1], b"", good[2]])
    one.put_raw("bob", batch)
    assert bob.contents() == ["n(0)", "n(1)", "n(2)"]
    assert bob.groups == [3]
    assert dict(two.dropped) == {"not_json": 1, "foreign_mas": 1, "too_large": 1}


def test_a_batch_over_the_batch_limit_is_dropped_whole(pair):
    one, two, bob = pair
    line = Envelope("m", "alice", ("bob",), "tell", "x" * 900).encode()
    one.put_raw("bob", b"\n".join([line] * (BATCH_BYTES // len(line) + 1)))
    assert bob.envelopes == [] and dict(two.dropped) == {"too_large": 1}


@pytest.mark.parametrize("payload, parts", [
    (b'{"a":1}', [b'{"a":1}']),
    (b'{"a":1}\n{"b":2}\n', [b'{"a":1}', b'{"b":2}']),
    (b'{\n  "a": 1\n}', [b'{\n  "a": 1\n}']),  # one message written over several lines
])
def test_split_batch(payload, parts):
    assert split_batch(payload) == parts


def test_one_message_written_over_several_lines_is_still_one_message(pair):
    one, two, bob = pair
    data = json.loads(Envelope("m", "alice", ("bob",), "tell", "p(1)").encode())
    one.put_raw("bob", json.dumps(data, indent=2).encode())
    assert bob.contents() == ["p(1)"] and not two.dropped


@settings(max_examples=150, deadline=None)
@given(st.text(max_size=40).map(lambda t: t * 12))
def test_long_contents_are_written_exactly_as_json_writes_them(content):
    assert _quote_content(content) == _quote(content)
    envelope = Envelope("m", "alice", ("bob",), "tell", content)
    assert decode(envelope.encode()) == envelope


def test_make_envelope_checks_what_is_unusual():
    usual = make_envelope("m", "alice", ("bob",), "tell", "p", None, "a.1")
    assert usual == Envelope("m", "alice", ("bob",), "tell", "p", None, "a.1")
    with pytest.raises(ValueError, match="to must be"):
        make_envelope("m", "alice", ("b/ob",), "tell", "p", None, "a.1")
    with pytest.raises(ValueError, match="unknown_performative"):
        make_envelope("m", "alice", ("bob",), "shout", "p", None, "a.1")


_raw = st.text(alphabet=st.sampled_from('ab"\\\n\x01é{},:'), max_size=4)


@settings(max_examples=300, deadline=None)
@given(st.lists(_raw, min_size=6, max_size=6), st.one_of(st.none(), _raw))
def test_the_own_form_fast_path_reads_what_json_reads(fields, reply):
    from agents.transport.envelope import _decode_well_formed, _read_own_form

    for name in ("m", "alice", "bob"):
        make_envelope(name, "alice", ("bob",), "tell", "", None, "1")  # names known, as after a first message
    message_id, mas, sender, receiver, perf, content = fields
    text = (f'{{"v":1,"id":"{message_id or "1"}","mas":"{mas or "m"}","from":"{sender or "alice"}",'
            f'"to":["{receiver or "bob"}"],"perf":"{perf or "tell"}","content":"{content}"'
            + ("}" if reply is None else f',"re":"{reply}"}}'))
    fast = _read_own_form(text)
    try:
        slow = _decode_well_formed(json.loads(text))
    except ValueError:
        slow = None
    assert fast is None or fast == slow, text


def test_a_message_nested_too_deep_is_refused_and_the_rest_of_its_batch_delivered(pair):
    one, two, bob = pair
    good = Envelope("m", "alice", ("bob",), "tell", "p").encode()
    two.max_message_size = 10_000
    one.put_raw("bob", b"\n".join([good, b"[" * 4_000 + b"]" * 4_000, good]))
    assert bob.contents() == ["p", "p"] and dict(two.dropped) == {"not_json": 1}
