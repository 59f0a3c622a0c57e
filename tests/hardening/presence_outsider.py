"""An outsider process for the secure presence test (tests/hardening/test_secure_presence.py): with a key of
its own, it declares liveliness tokens on a member's name and on a name that is no member, puts heartbeats
that prove nothing (unsigned, signed with its own key) and forged ``.progress`` reports, prints ``READY``, then
keeps its tokens up, putting the same heartbeats again every half second, until killed."""
from __future__ import annotations

import argparse
import time

from agents.transport import ZenohOptions, ZenohTransport
from agents.transport.identity import load_private_key
from tests.hardening.outsider_attacks import claim_alive, forge_heartbeats, forge_progress


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--mas", required=True)
    parser.add_argument("--connect", required=True)
    parser.add_argument("--key", required=True, help="the outsider's own private key (PEM)")
    parser.add_argument("--names", required=True, help="names to claim alive, comma-separated")
    parser.add_argument("--progress-as", required=True, help="the member whose .progress reports are forged")
    args = parser.parse_args()
    own_key = load_private_key(args.key)
    names = args.names.split(",")
    with ZenohTransport(args.mas, ZenohOptions(mode="client", connect=(args.connect,))) as transport:
        tokens = claim_alive(transport.session, args.mas, names)
        forge_heartbeats(transport.session, args.mas, names, own_key)
        forge_progress(transport, args.mas, args.progress_as, "diagnosed", "evil", own_key)
        time.sleep(0.5)
        print("READY", flush=True)
        while tokens:   # the tokens stay up; the heartbeats come again (they must never prove anything)
            time.sleep(0.5)
            forge_heartbeats(transport.session, args.mas, names, own_key)


if __name__ == "__main__":
    main()
