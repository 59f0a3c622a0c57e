"""A child process for the hostile-message tests: one agent on the in-memory transport (``wire``: every
message is encoded and decoded as on the network) receives the payloads named on the command line, then
one valid tell. It prints ``ALIVE {"dropped": {payload: counters}, "beliefs": [...]}`` and exits 0 if it survived; a process
killed by SIGSEGV (the compiled interpreter overflowing the C stack) prints nothing and exits -11.

Run in its own process because the failure it guards against kills the process."""
from __future__ import annotations

import json
import sys

from agents.transport import Envelope, LocalBus, LocalTransport
from agents.zenoh_arch import TransportBridge
from agentspeak.runtime import LocalRuntime
from tests.hardening.payloads import HOSTILE


def main(names: list[str]) -> int:
    bus = LocalBus()
    runtime = LocalRuntime(printer=lambda name, text: None)
    runtime.add_agent("bob", "+ok <- .print(fine).\n")
    with LocalTransport("m", bus, wire=True) as mine, LocalTransport("m", bus, wire=True) as outside:
        TransportBridge(runtime, mine, declared=["bob", "alice"]).attach()
        dropped = {}
        for name in names:
            before = dict(mine.dropped)
            outside.put_raw("bob", HOSTILE[name]())
            dropped[name] = {k: v - before.get(k, 0) for k, v in mine.dropped.items() if v != before.get(k, 0)}
        outside.register("alice", lambda envelope: None)
        outside.send(Envelope("m", "alice", ("bob",), "tell", "ok"))
        runtime.run(timeout=10.0)
        beliefs = sorted(str(b) for b in runtime.agents["bob"].bb.literals())
        print("ALIVE", json.dumps({"dropped": dropped, "beliefs": beliefs}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
