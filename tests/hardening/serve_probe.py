"""How the simulator-serving process's memory behaves world after world (issue 22's leak): ``N`` team worlds
of six robots with cameras, each served over a Zenoh hub for ``--hold`` seconds and shut down, in this one
process; after each, what resident memory is made of (``memory.memory_breakdown``) and Python's gc-tracked
objects.

``python -m tests.hardening.serve_probe --worlds 12 --hold 3``. Figures in docs/reliability.md ("Soak")."""
from __future__ import annotations

import argparse
import gc
import time

from tests.hardening.memory import memory_breakdown


def main(argv: list[str] | None = None) -> int:
    from agents.cooperative import build_world, team_scenario
    from agents.transport import ZenohOptions, ZenohTransport, loopback_endpoint
    from robot_bridge.sim.server import SimServer

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", type=int, default=12)
    parser.add_argument("--hold", type=float, default=3.0, help="wall seconds each world is served")
    args = parser.parse_args(argv)
    for i in range(args.worlds):
        scenario = team_scenario(6, 1, 1000 + i)
        world, bridges = build_world(scenario)
        hub = ZenohTransport(scenario.mas, ZenohOptions(listen=(loopback_endpoint(),))).open()
        server = SimServer(hub.session, scenario.mas, bridges).start()
        time.sleep(args.hold)
        server.stop()
        for bridge in bridges.values():
            bridge.shutdown()
        hub.close()
        del world, bridges, server
        gc.collect()
        print(f"world {i + 1}: resident MiB {memory_breakdown()}, gc objects {len(gc.get_objects())}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
