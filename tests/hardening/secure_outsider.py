"""An outsider process for the secure-profile test: it knows the MAS name, the key layout, the envelope
format and has a key pair of its own (``--key``, not listed in the project). It listens on bob's inbox
until a member (alice) has sent bob something, then tries, each as a separate network message: unsigned
tells and goals, its own signed tell/achieve/tellHow/askOne, a forged ``from`` signed with its own key,
alice's captured message replayed and tampered with, and stops (unsigned under a member's name, signed
by itself, claiming to be the launcher). Prints ``READY`` once listening and ``SENT`` when done."""
from __future__ import annotations

import argparse
import threading
import time

from agents.transport import ZenohOptions, ZenohTransport
from agents.transport.identity import load_private_key
from agents.transport.keys import inbox_key
from tests.hardening.outsider_attacks import attack_inbox, attack_stop


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--mas", required=True)
    parser.add_argument("--connect", required=True)
    parser.add_argument("--key", required=True, help="the outsider's own private key (PEM)")
    args = parser.parse_args()
    mas = args.mas
    own_key = load_private_key(args.key)
    captured: list[bytes] = []
    seen_alice = threading.Event()

    def capture(sample) -> None:
        for line in sample.payload.to_bytes().split(b"\n"):
            if b'"from":"alice"' in line and b'"perf":"tell"' in line and b'"sig":"' in line:
                captured.append(line)
                seen_alice.set()

    with ZenohTransport(mas, ZenohOptions(mode="client", connect=(args.connect,))) as transport:
        assert transport.wait_for_agents(["bob"], timeout=30), "bob never appeared"
        session = transport.session
        spy = session.declare_subscriber(inbox_key(mas, "bob"), capture)
        time.sleep(0.5)  # the subscription reaches the routing tables before alice is started
        print("READY", flush=True)
        assert seen_alice.wait(60), "alice sent bob nothing"

        def put(payload: bytes) -> None:
            session.put(inbox_key(mas, "bob"), payload)

        attack_inbox(put, mas, "bob", "alice", own_key, goal="act", query="secret(X)")
        original = captured[0]
        put(original)                                                           # a replay
        put(original.replace(b"hello_from(alice)", b"hello_from(evil)"))        # tampered
        attack_stop(transport, mas, "alice", own_key)
        time.sleep(0.5)  # let the puts leave before the session closes
        spy.undeclare()
    print("SENT", flush=True)


if __name__ == "__main__":
    main()
