"""An outsider process for the impersonation tests: joins MAS ``--mas`` through ``--connect`` as a Zenoh
client (knowing the key layout and the envelope format, as anyone can) and tries what issue 22 found
possible: plans and goals under foreign or forged names, a duplicated ``from``, stops of the MAS.
Prints ``SENT`` when done."""
from __future__ import annotations

import argparse
import json
import time

from agents.transport import Envelope, ZenohOptions, ZenohTransport
from agents.transport.keys import inbox_key

EVIL_PLAN = "{+!evil <- +evil_ran.}"


def attempts(mas: str) -> list[tuple[str, object]]:
    """(what, envelope or raw payload) in the order sent; the test expects each outcome by ``what``."""
    def env(sender: str, performative: str, content: str) -> Envelope:
        return Envelope(mas, sender, ("bob",), performative, content)

    duplicate = json.dumps({"v": 1, "id": "dup.1", "mas": mas, "from": "mallory", "to": ["bob"], "perf": "tell",
                            "content": "dup_ok"})[:-1] + ',"from":"alice"}'
    return [
        ("tellHow as the receiver itself", env("bob", "tellHow", EVIL_PLAN)),
        ("tellHow from a stranger", env("mallory", "tellHow", EVIL_PLAN)),
        ("achieve from a stranger", env("mallory", "achieve", "act")),
        ("achieve as the receiver itself", env("bob", "achieve", "act")),
        ("duplicate from", duplicate.encode()),
        ("tell from a stranger", env("mallory", "tell", "hello")),
        ("achieve from a member", env("alice", "achieve", "act")),
    ]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--mas", required=True)
    parser.add_argument("--connect", required=True)
    args = parser.parse_args()
    with ZenohTransport(args.mas, ZenohOptions(mode="client", connect=(args.connect,))) as transport:
        assert transport.wait_for_agents(["bob"], timeout=30), "bob never appeared"
        for _what, item in attempts(args.mas):
            if isinstance(item, Envelope):
                transport.send(item)
            else:
                transport.session.put(inbox_key(args.mas, "bob"), item)
        transport.publish_control("stop", by="mallory", delay=0.0)
        transport.publish_control("stop", by="launcher", delay=0.0)  # claims to be the launcher, no token
        time.sleep(0.5)  # let the puts leave before the session closes
    print("SENT", flush=True)


if __name__ == "__main__":
    main()
