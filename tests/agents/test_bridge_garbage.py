"""An agent process that stays up (issue 22's soak) collects the garbage its finished intentions leave in
reference cycles when its agents go idle (agents/zenoh_arch.py ``IDLE_COLLECT_S``), rather than letting it pile up
until Python's gc gets round to a full collection."""
from __future__ import annotations

import gc

from agents import zenoh_arch
from agents.transport import LocalBus, LocalTransport
from agents.zenoh_arch import TransportBridge
from agentspeak.runtime import LocalRuntime
from agentspeak.stdlib.registry import Suspend
from tests.agents.transport_fixtures import unique_mas


def test_an_idle_agent_process_collects_the_garbage_of_its_finished_intentions(monkeypatch):
    monkeypatch.setattr(zenoh_arch, "IDLE_COLLECT_S", 0.0, raising=False)
    runtime = LocalRuntime()
    runtime.add_agent("a", "!go.\n+!go <- for ( .range(I, 1, 50) ) { .wait(1) }; .print(done).\n")
    transport = LocalTransport(unique_mas("garbage"), LocalBus()).open()
    bridge = TransportBridge(runtime, transport, declared=["a"]).attach()
    gc.collect()
    # other tests' (still referred to): not this agent's. Held here, so that one of them freed meanwhile (an
    # earlier test's thread ending) neither lowers the count nor lends its id to a new one
    others = [o for o in gc.get_objects() if type(o) is Suspend]
    known = {id(o) for o in others}
    gc.disable()     # only the bridge's own collection may run
    try:
        assert bridge.run(timeout=1.5) == "timeout"
        left = sum(type(o) is Suspend and id(o) not in known for o in gc.get_objects())
    finally:
        gc.enable()
        bridge.detach()
        transport.close()
    assert left == 0, f"{left} suspensions of finished waits still in memory"
