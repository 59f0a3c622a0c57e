"""A Zenoh peer for the observer tests, in its own process: listens on ENDPOINT, publishes JSON
``{"data": x}`` on KEY at RATE Hz and holds a liveliness token ``faultmas/test/alive/NAME``.
``python zenoh_publisher.py ENDPOINT KEY RATE NAME``; prints ``ready``; SIGTERM ends it."""
from __future__ import annotations

import json
import signal
import sys
import threading

import zenoh


def main() -> int:
    endpoint, key, rate, name = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]
    config = zenoh.Config()
    config.insert_json5("mode", json.dumps("peer"))
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("listen/endpoints", json.dumps([endpoint]))
    session = zenoh.open(config)
    token = session.liveliness().declare_token(f"faultmas/test/alive/{name}")
    pub = session.declare_publisher(key)
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    print("ready", flush=True)
    n = 0
    while not stop.wait(1.0 / rate):
        pub.put(json.dumps({"data": 12.0, "n": n}))
        n += 1
    token.undeclare()
    session.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
