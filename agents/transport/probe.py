"""A stand-alone transport endpoint for checking a deployment, and for the tests and benchmark:
``python -m agents.transport.probe echo|flood --mas M --name N [--connect EP ...]``.

* ``echo``: registers agent N and answers every message with the same performative and content,
  ``in_reply_to`` set, to its sender (a ping target to check that two hosts reach each other).
* ``flood``: waits for agent ``--to``, then sends ``--valid`` numbered ``tell seq(I)`` messages
  interleaved with ``--bad`` malformed or oversized payloads on its inbox key (robustness check).

Prints ``READY <endpoints as JSON>`` once it is reachable, then runs until a ``stop`` control
message, end of standard input, or (flood) the last message.
"""
from __future__ import annotations

import argparse
import json
import sys
import threading
from collections import Counter
from typing import Sequence

from agents.transport.base import Inbox
from agents.transport.config import ZenohOptions
from agents.transport.envelope import DEFAULT_MAX_SIZE, Envelope
from agents.transport.zenoh_transport import ZenohTransport


def bad_payloads(mas: str, sender: str, receiver: str, max_size: int) -> list[tuple[str, bytes]]:
    """One payload per drop reason (reason, bytes): what a broken or hostile peer may put."""
    def envelope(**change: object) -> bytes:
        data: dict[str, object] = {"v": 1, "id": "x.1", "mas": mas, "from": sender, "to": [receiver],
                                   "perf": "tell", "content": "ok"}
        data.update(change)
        return json.dumps({k: v for k, v in data.items() if v is not None}).encode()

    return [
        ("not_json", b"\xff\xfe not even text"),
        ("not_json", b'["a", "list"]'),
        ("bad_version", envelope(v=99)),
        ("missing_field", envelope(content=None)),
        ("bad_field_type", envelope(to="bob/../*")),
        ("bad_field_type", envelope(content=["x"])),
        ("unknown_performative", envelope(perf="launchMissiles")),
        ("foreign_mas", envelope(mas="othermas")),
        ("not_addressed", envelope(to=["somebody_else"])),
        ("too_large", envelope(content="x" * max_size)),
    ]


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m agents.transport.probe", description=__doc__.splitlines()[0])
    parser.add_argument("mode", choices=("echo", "flood"))
    parser.add_argument("--mas", required=True)
    parser.add_argument("--name", required=True)
    parser.add_argument("--connect", action="append", default=[], metavar="ENDPOINT")
    parser.add_argument("--listen", action="append", default=None, metavar="ENDPOINT")
    parser.add_argument("--config", default=None, metavar="FILE", help="Zenoh JSON5 (TLS, auth, ACL)")
    parser.add_argument("--to", default=None, help="flood: the receiving agent")
    parser.add_argument("--valid", type=int, default=100, help="flood: valid messages")
    parser.add_argument("--bad", type=int, default=1000, help="flood: bad payloads")
    parser.add_argument("--max-size", type=int, default=DEFAULT_MAX_SIZE,
                        help="flood: the receiver's size limit (oversized payloads exceed it)")
    args = parser.parse_args(argv)
    options = ZenohOptions(listen=tuple(args.listen) if args.listen else None, connect=tuple(args.connect),
                           config_file=args.config)
    stop = threading.Event()
    with ZenohTransport(args.mas, options) as transport:
        transport.on_control(lambda message: stop.set() if message.get("command") == "stop" else None)
        threading.Thread(target=lambda: (sys.stdin.read(), stop.set()), daemon=True).start()
        if args.mode == "echo":
            inbox = Inbox()
            transport.register(args.name, inbox)
            print("READY", json.dumps(transport.endpoints), flush=True)
            while not stop.is_set():
                message = inbox.get(timeout=0.1)
                if message is not None:
                    transport.send(message.reply(message.performative, message.content, sender=args.name))
        else:
            transport.register(args.name, Inbox())
            print("READY", json.dumps(transport.endpoints), flush=True)
            if not args.to or not transport.wait_for_agents([args.to], timeout=30):
                print(f"flood: agent {args.to!r} not alive", file=sys.stderr)
                return 1
            sent_bad = flood(transport, args.name, args.to, args.valid, args.bad, args.max_size)
            print("DONE", json.dumps(sent_bad), flush=True)
            stop.wait(30)  # let the receiver read everything before this session closes
    return 0


def flood(transport: ZenohTransport, sender: str, receiver: str, valid: int, bad: int,
          max_size: int) -> Counter[str]:
    """Send ``valid`` numbered tells spread evenly among ``bad`` bad payloads, in one FIFO stream;
    return how many bad payloads of each drop reason were sent."""
    payloads = bad_payloads(transport.mas, sender, receiver, max_size)
    sent_bad: Counter[str] = Counter()
    sent_valid = 0
    for i in range(valid + bad):
        if sent_valid < valid and i * valid >= sent_valid * (valid + bad):
            transport.send(Envelope(transport.mas, sender, (receiver,), "tell", f"seq({sent_valid})"))
            sent_valid += 1
        else:
            reason, payload = payloads[sum(sent_bad.values()) % len(payloads)]
            transport.put_raw(receiver, payload)
            sent_bad[reason] += 1
    return sent_bad

if __name__ == "__main__":
    sys.exit(main())
